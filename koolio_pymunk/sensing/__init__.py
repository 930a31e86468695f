"""The sensing floor: what the robot reads and how it is encoded.

The sensor suite (sonar ring, cameras, compass, noise, Tables 6 and 7:
:mod:`.suite`), the ray engines (pymunk reference and compiled: :mod:`.ray_engines`),
the compiled whole-reading kernel (:mod:`.ray_kernel`) and read-out (noise, encoding,
state key: :mod:`.encoding_kernel`), the realism models (:mod:`.realism`,
:mod:`.realism_kernel`) and the fast-against-reference comparison (:mod:`.agreement`).

Imports only from :mod:`koolio_pymunk.world` and :mod:`koolio_pymunk.store`.
"""
