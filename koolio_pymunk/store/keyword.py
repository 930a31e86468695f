"""The Q-table keyword (paper Table 12): state fields and the action packed in one integer.

A state is a tuple of sensor codes (goal cameras, end-of-world cameras, sonar groups,
then the compass if it is in the state); the keyword shifts each code into its own bit
field and the action into the low bits. :class:`KeywordLayout` computes the shifts and
the sizes the paper discusses (§5.4.8). The encoded levels of each sensor kind are named
here too (:data:`SONAR_LEVELS`, :data:`CAMERA_LEVELS`, :data:`COMPASS_LEVELS`).

>>> lay = KeywordLayout((("GoalCam0", 3), ("Sonar0", 4)))
>>> lay.shifts, lay.action_bits, lay.total_bits
((5, 3), 3, 7)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..robot_runtime import field_bits

N_ACTIONS = 5


#: Keywords are 64-bit (state keys are stored as uint64 and handled as int64).
MAX_KEYWORD_BITS = 64


#: Largest number of codes of one state field, and of actions, a file may declare.
MAX_LEVELS = 1 << 16


MAX_ACTIONS = 64


@dataclass(frozen=True)
class KeywordLayout:
    """Bit layout of the keyword: state fields (name, levels), most significant first."""

    fields: tuple[tuple[str, int], ...]
    n_actions: int = N_ACTIONS

    @property
    def bits(self) -> tuple[int, ...]:
        """Bits of each field: ``max(1, ceil(log2(levels)))``, in integers (exact)."""
        return tuple(field_bits(levels) for _, levels in self.fields)

    @property
    def action_bits(self) -> int:
        return field_bits(self.n_actions)

    @property
    def shifts(self) -> tuple[int, ...]:
        """Shift of each field within the keyword (Table 12's ``<<`` numbers)."""
        out, pos = [], self.action_bits
        for b in reversed(self.bits):
            out.append(pos)
            pos += b
        return tuple(reversed(out))

    @property
    def total_bits(self) -> int:
        return sum(self.bits) + self.action_bits

    @property
    def n_states(self) -> int:
        return math.prod(levels for _, levels in self.fields)

    @property
    def n_entries(self) -> int:
        return self.n_states * self.n_actions

    def dense_bytes(self, value_bytes: int = 8) -> int:
        """Bytes of a dense table of doubles (paper: 113.9 MiB)."""
        return self.n_entries * value_bytes

    def state_key(self, codes: Sequence[int]) -> int:
        key = 0
        for code, b in zip(codes, self.bits):
            key = (key << b) | code
        return key

    def keyword(self, codes: Sequence[int], action: int) -> int:
        """The Table 12 keyword of ``codes`` and ``action``."""
        return (self.state_key(codes) << self.action_bits) | action

    def decode(self, keyword: int) -> tuple[tuple[int, ...], int]:
        """``(codes, action)`` of a keyword."""
        action = keyword & ((1 << self.action_bits) - 1)
        key = keyword >> self.action_bits
        codes = []
        for b in reversed(self.bits):
            codes.append(key & ((1 << b) - 1))
            key >>= b
        return tuple(reversed(codes)), action

    def to_json(self) -> dict[str, Any]:
        return {
            "fields": [[n, lv] for n, lv in self.fields],
            "action_bits": self.action_bits,
            "n_actions": self.n_actions,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> KeywordLayout:
        return cls(tuple((str(n), int(lv)) for n, lv in data["fields"]), int(data["n_actions"]))


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
