"""The sensing floor: what the robot reads and how it is encoded.

The sensor suite (sonar ring, cameras, compass, noise, Tables 6 and 7:
:mod:`.suite`), the ray engines (pymunk reference and compiled: :mod:`.ray_engines`),
the compiled whole-reading kernel (:mod:`.ray_kernel`) and read-out (noise, encoding,
state key: :mod:`.encoding_kernel`), the realism models (:mod:`.realism`,
:mod:`.realism_kernel`), the robot's memory in its state (:mod:`.memory`), the kernels'
inputs (:mod:`.sensor_arrays`) and their inline twins (:mod:`.inline_twins`). The
fast-against-reference comparison is the tools' and the tests' (``tools/sensing_agreement.py``).

Imports only from :mod:`koolio_pymunk.world` and :mod:`koolio_pymunk.store`.
"""
