"""The compiled sensing kernels' inputs, grouped: a few tuples of arrays built once.

A kernel of :mod:`~koolio_pymunk.sensing.ray_kernel`,
:mod:`~koolio_pymunk.sensing.encoding_kernel` or
:mod:`~koolio_pymunk.sensing.realism_kernel` takes each group as one argument and unpacks
it in its first line, so its signature reads in one line. Plain tuples (numba types them
field by field, and a call costs what the separate arguments cost; a named tuple or a
structref costs a measurable fraction of a microsecond more per call). Each group's fields,
in order, are the names below; :class:`~koolio_pymunk.sensing.suite.KernelInputs` builds
them once per sensor suite (:class:`~.reading_kernel.ReadingArrays` stacks N robots').

* **geometry** (:data:`GEOMETRY`): what a reading's rays and cameras need of the sensor
  suite and the walls;
* **buffers** (:data:`BUFFERS`): one robot's working arrays of a reading (written);
* **encoding** (:data:`ENCODING`): the read-out's noise fractions, limits, thresholds,
  sonar groups and key layout;
* **realism** (:data:`REALISM`): the sonar and camera models' parameters and what they
  report of a reading (:class:`~koolio_pymunk.sensing.realism.SensorRealism`'s layout);
* **others** (:data:`OTHERS`, a shared world's readings only): the other robots and
  which of them the reading met (:func:`~koolio_pymunk.sensing.ray_kernel.sense_among`).

>>> GEOMETRY
('ray_offsets', 'ray_units', 'params', 'camera_dirs', 'markers', 'walls')
"""

from __future__ import annotations

#: Ray offsets (n_sonar x sub_arcs, radians) and their unit vectors (2 x n_sonar x
#: sub_arcs: ``suite.unit_vectors``), ``params`` (see ``ray_kernel.sense_one``), camera
#: directions (radians), end-of-world markers (n x 2), walls (``wall_array``).
GEOMETRY = ("ray_offsets", "ray_units", "params", "camera_dirs", "markers", "walls")
#: Noise-free readings, ray distances, marker seen per camera, trigonometry cache,
#: incidence cosine per ray, other plate per camera, room for the lists of walls near the
#: robot and near a sonar's rays (``ray_kernel.new_wall_lists``: working space only).
BUFFERS = ("raw", "rays", "eow_k", "trig", "ray_cos", "decoy", "wall_lists")
#: Noise fraction per reading, sonar count, ``[really_long_distance, max_camera_view]``,
#: sonar and camera thresholds, sonar group members and sizes, bits per state field,
#: whether the compass is in the state.
ENCODING = (
    "fracs", "n_sonar", "limits", "sonar_thresholds", "camera_thresholds", "group_members",
    "group_sizes", "bits", "compass_in_state",
)  # fmt: skip
#: The realism models' parameters and flags, sonar neighbours, then what they report:
#: echo per ray, crosstalk per sonar, missed detections and misreads per camera; room for
#: the sonar models' working values (``realism_kernel.new_work``).
REALISM = ("params", "flags", "neighbours", "echo", "crossed", "missed", "misread", "work")


#: Every robot's centre (``(N, 2)`` float64, the reader's own row ignored), whether each
#: is in the arena (``(N,)`` bool), the reading robot's index; written: the robot each
#: sub-arc ray hit (n_sonar x sub_arcs) and each sonar read (n_sonar), -1 for a wall or
#: nothing.
OTHERS = ("robots", "present", "me", "ray_robot", "sonar_robot")


def bundle(fields: tuple[str, ...], source: object, **values: object) -> tuple:
    """The tuple of ``fields``: each from ``values`` when given there, else the attribute
    of ``source`` of that name.

    >>> from types import SimpleNamespace
    >>> bundle(("a", "b"), SimpleNamespace(a=1, b=2), b=3)
    (1, 3)
    """
    return tuple(values[f] if f in values else getattr(source, f) for f in fields)
