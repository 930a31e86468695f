"""The task floor: the paper's delivery task as a Gymnasium environment.

:class:`~koolio_pymunk.task.env.KoolioEnv` (:mod:`.env`), its registered Gymnasium ids
(:mod:`.registry`), the no-undo rule (:mod:`.action_rules`: the env's action mask and the
learners' choice), the reward rules (:mod:`.rules`), auto rescue (:mod:`.rescue`), the
end-of-world zones (:mod:`.end_zones`), and the env's drawing (:mod:`.render`,
:mod:`.drawing`, :mod:`.viewport`; pygame is imported only when something is drawn).

Imports only from the floors below: sensing, world, store.
"""
