"""The learning floor: the learners on top of the task (the Q-table they learn into,
and its files, are the store's: :mod:`koolio_pymunk.store.qtable`).

One-step Q (:mod:`.qlearning`),
Q(lambda) (:mod:`.qlambda`), Dyna-Q (:mod:`.dyna`), the algorithm registry
(:mod:`.algorithms`), training (:mod:`.training`), evaluation, the periodic checks and
the best table kept (:mod:`.evaluation`); the episode loop, one robot or N in tick
order (:mod:`.episodes`: the reference), and the step engine that runs them compiled
(:mod:`.engine`, on :mod:`.table_kernel`).

Imports only from the floors below: task, sensing, world, store.
"""
