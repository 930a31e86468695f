"""The world floor: arenas and the pymunk space the robot moves in.

Arena files and their validation (:mod:`.arena`), polygon geometry (:mod:`.geometry`),
the hallway built from a door table (:mod:`.hallway`), the pymunk space with its walls,
robot bodies and the five actions (:mod:`.physics`), the motion errors of a real drive
(:mod:`.motion_errors`), and the compiled twins of Chipmunk's segment query
(:mod:`.segment_query`) and of a whole move (:mod:`.swept_move`), held to the pymunk
world by ``tools/move_agreement.py``.

Imports only from :mod:`koolio_pymunk.store`.
"""
