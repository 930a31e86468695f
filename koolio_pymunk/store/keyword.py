"""The Q-table keyword (paper Table 12): state fields and the action packed in one integer.

A state is a tuple of sensor codes (goal cameras, end-of-world cameras, sonar groups,
then the compass if it is in the state); the keyword shifts each code into its own bit
field and the action into the low bits. The arithmetic is the robot's:
:class:`KeywordLayout` is the runtime's :class:`~koolio_pymunk.robot_runtime.Layout`
(bits, shifts, keyword, decode, the policy file's ``layout``), compared by its fields,
with the sizes the paper discusses (§5.4.8) and the Q-table header's form. The encoded
levels of each sensor kind are named here too (:data:`SONAR_LEVELS`,
:data:`CAMERA_LEVELS`, :data:`COMPASS_LEVELS`).

>>> lay = KeywordLayout((("GoalCam0", 3), ("Sonar0", 4)))
>>> lay.shifts, lay.action_bits, lay.total_bits
((5, 3), 3, 7)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..robot_runtime import Layout

N_ACTIONS = 5


#: Keywords are 64-bit (state keys are stored as uint64 and handled as int64).
MAX_KEYWORD_BITS = 64


#: Largest number of codes of one state field, and of actions, a file may declare.
MAX_LEVELS = 1 << 16


MAX_ACTIONS = 64


class KeywordLayout(Layout):
    """Bit layout of the keyword: state fields (name, levels), most significant first.

    The robot runtime's :class:`~koolio_pymunk.robot_runtime.Layout`, so a table and the
    policy exported from it encode alike by construction; equal (and hashed) by its
    fields and action count. Not to be changed once made.

    >>> lay = KeywordLayout((("A", 3), ("B", 4)))
    >>> lay.fields, lay.bits, lay.keyword((2, 1), 3), lay.decode(75)
    ((('A', 3), ('B', 4)), (2, 2), 75, ((2, 1), 3))
    >>> lay == KeywordLayout([("A", 3), ("B", 4)], 5), lay == KeywordLayout((("A", 3),))
    (True, False)
    """

    def __init__(self, fields: Sequence[tuple[str, int]], n_actions: int = N_ACTIONS) -> None:
        super().__init__(fields, n_actions)
        self.fields: tuple[tuple[str, int], ...] = tuple(zip(self.names, self.levels))
        """``(name, levels)`` of each state field, most significant first."""

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, KeywordLayout):
            return NotImplemented
        return (self.fields, self.n_actions) == (other.fields, other.n_actions)

    def __hash__(self) -> int:
        return hash((self.fields, self.n_actions))

    def __repr__(self) -> str:
        return f"KeywordLayout({self.fields!r}, n_actions={self.n_actions})"

    @property
    def n_states(self) -> int:
        """States the fields can encode (the rows of a dense table)."""
        return math.prod(self.levels)

    @property
    def n_entries(self) -> int:
        """Entries of a dense table: states times actions."""
        return self.n_states * self.n_actions

    def dense_bytes(self, value_bytes: int = 8) -> int:
        """Bytes of a dense table of doubles (paper: 113.9 MiB)."""
        return self.n_entries * value_bytes

    def header_json(self) -> dict[str, Any]:
        """The Q-table header's ``layout`` (:mod:`koolio_pymunk.store.qtable`); the
        policy file's is :meth:`to_json`."""
        return {
            "fields": [[n, lv] for n, lv in self.fields],
            "action_bits": self.action_bits,
            "n_actions": self.n_actions,
        }


#: The leading state field of a table that holds each robot's own rows (``train --tables
#: each``): the robot's index, so that no row is shared.
ROBOT_FIELD = "Robot"


def own_tables(layout: KeywordLayout, robots: int) -> KeywordLayout:
    """``layout`` with :data:`ROBOT_FIELD` of ``robots`` levels first (most significant):
    the layout of a table holding ``robots`` robots' own tables, robot ``k``'s rows those
    whose state key is its own key plus :func:`robot_offset` ``(layout, k)``.

    >>> lay = own_tables(KeywordLayout((("A", 3), ("B", 4))), 4)
    >>> lay.fields, lay.state_key((2, 1, 3)) == robot_offset(lay, 2) + (1 << 2 | 3)
    ((('Robot', 4), ('A', 3), ('B', 4)), True)
    >>> table_robots(lay), table_robots(base_layout(lay)), base_layout(lay).fields
    (4, 0, (('A', 3), ('B', 4)))
    """
    own = KeywordLayout(((ROBOT_FIELD, robots),) + layout.fields, layout.n_actions)
    if own.total_bits > MAX_KEYWORD_BITS:
        raise ValueError(
            f"the keyword with the robot's index ({robots} robots: {own.bits[0]} bits) would "
            f"need {own.total_bits} bits; it must fit {MAX_KEYWORD_BITS}"
        )
    return own


def table_robots(layout: KeywordLayout) -> int:
    """How many robots' own tables a table of ``layout`` holds (0: one table all share)."""
    if layout.fields and layout.fields[0][0] == ROBOT_FIELD:
        return layout.fields[0][1]
    return 0


def base_layout(layout: KeywordLayout) -> KeywordLayout:
    """The layout of one robot's rows (``layout`` without :data:`ROBOT_FIELD`)."""
    if not table_robots(layout):
        return layout
    return KeywordLayout(layout.fields[1:], layout.n_actions)


def robot_offset(layout: KeywordLayout, robot: int) -> int:
    """What robot ``robot``'s state keys add in a table of ``layout`` (0 when the robots
    share one table): its index shifted above the other state fields."""
    if not table_robots(layout):
        return 0
    return robot << sum(layout.bits[1:])


#: Codes of the sonar intervals (Table 6) and camera intervals (Table 7).
SONAR_LEVELS = ("Bump", "Close", "Medium", "Far")


CAMERA_LEVELS = ("Close", "Medium", "Far")


COMPASS_LEVELS = ("East", "North", "West", "South")


#: The paper's first design (§5.4.8): compass (4 values), 6 cameras (4 values: Close,
#: Medium, Far, Very Far) and 8 sonars (5 values), before it was cut down.
PAPER_ORIGINAL_FIELDS: tuple[tuple[str, int], ...] = (
    (("Compass", 4),)
    + tuple((f"Camera{c}", 4) for c in range(6))
    + tuple((f"Sonar{s}", 5) for s in range(8))
)
