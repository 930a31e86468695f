"""The learning floor: the Q-table and the learners on top of the task.

The sparse Q-table and its file (:mod:`.qtable`), one-step Q (:mod:`.qlearning`),
Q(lambda) (:mod:`.qlambda`), Dyna-Q (:mod:`.dyna`), the algorithm registry
(:mod:`.algorithms`), training (:mod:`.training`), evaluation, the periodic checks and
the best table kept (:mod:`.evaluation`); the episode loop, one robot or N in tick
order (:mod:`.episodes`: the reference), and the step engine that runs them compiled
(:mod:`.engine`, on :mod:`.table_kernel`).

Imports only from the floors below: task, sensing, world, store.
"""
