"""The learning floor: the Q-table and the learners on top of the task.

The sparse Q-table and its file (:mod:`.qtable`), one-step Q (:mod:`.qlearning`),
Q(lambda) (:mod:`.qlambda`), Dyna-Q (:mod:`.dyna`), the algorithm registry
(:mod:`.algorithms`), training (:mod:`.training`), evaluation, the periodic checks and
the best table kept (:mod:`.evaluation`), many robots on one
table (:mod:`.fleet`, compiled in :mod:`.fleet_kernel`).

Imports only from the floors below: task, sensing, world, store.
"""
