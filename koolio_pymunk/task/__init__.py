"""The task floor: the paper's delivery task as a Gymnasium environment.

:class:`~koolio_pymunk.task.env.KoolioEnv` (:mod:`.env`), the reward rules
(:mod:`.rules`), auto rescue (:mod:`.rescue`), the end-of-world zones
(:mod:`.end_zones`), and the env's drawing (:mod:`.render`, :mod:`.drawing`,
:mod:`.viewport`; pygame is imported only when something is drawn).

Imports only from the floors below: sensing, world, store.
"""
