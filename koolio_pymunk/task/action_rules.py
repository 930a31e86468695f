"""Which actions a learner may choose: the no-undo rule (``learner.no_undo``).

With the rule on, the robot never chooses the action that undoes the one it has just
taken: no RotateRight right after RotateLeft (and back), no Reverse right after Forward
(and back). Stop undoes nothing and is never barred. The first action of an episode, and
the first after an auto rescue (which moved the robot), are free. The rule holds for the
greedy choice and for the exploratory one alike, in training, in every evaluation, in
the window and on the robot (``robot_runtime.py`` repeats it), so a table is always read
the way it was learned. It lives on the task floor so that the env can say it too: its
``info["action_mask"]`` (:meth:`~koolio_pymunk.task.env.KoolioEnv.action_masks`) allows
what a learner under the rule may choose, for learners outside the package.

Why: the hallway's 27-bit state aliases. Facing the south wall the robot is in the
hallway's most common state, whose best action (RotateRight, learned facing north) turns
it to where RotateLeft is best, back to the first state: a memoryless greedy policy loops
there until the step cap. Barring the immediate undo breaks every two-step loop of that
kind without a bit more in the state (the previous action in the state, a memory, would
split every state in six and multiply the states to visit). Not in the paper (its
learner chooses among all five actions).

Not a change of the update: Table 11's ``max(NextQ)`` still runs over all five actions.

:func:`barred` and :func:`allowed_action` are plain Python that numba also compiles into
the step engine (:mod:`koolio_pymunk.learning.table_kernel`): this module is one of the
kernels' sources, and changing it clears their cache
(:mod:`koolio_pymunk.store.kernel_cache`).

Draws: with one action barred, an exploratory (or unvisited state's) action is
``integers(0, 4)`` mapped over the four others in index order, and greedy ties are broken
among the allowed ones; with none barred the draws are those of the rule off, so a run
with the rule off is the same, bit for bit, as before the rule existed.

>>> barred(1), barred(3), barred(0), barred(NONE)
(2, 4, -1, -1)
>>> [allowed_action(k, 2) for k in range(4)]
[0, 1, 3, 4]
"""

from __future__ import annotations

#: No action yet (an episode's start, or just after an auto rescue).
NONE = -1
#: By action index (Stop, RotateLeft, RotateRight, Forward, Reverse): the action that
#: undoes it (-1: none undoes Stop).
UNDO = (-1, 2, 1, 4, 3)


def barred(last: int) -> int:
    """The action the rule bars after ``last`` (:data:`NONE`: none barred, -1)."""
    return UNDO[last] if 0 <= last < len(UNDO) else -1


def allowed_action(k: int, bar: int) -> int:
    """The ``k``-th action (0-based, index order) that is not ``bar`` (-1: none barred)."""
    return k + 1 if 0 <= bar <= k else k


def allowed(n_actions: int, bar: int) -> list[int]:
    """Every action of ``n_actions`` but ``bar``.

    >>> allowed(5, 4), allowed(5, -1)
    ([0, 1, 2, 3], [0, 1, 2, 3, 4])
    """
    return [a for a in range(n_actions) if a != bar]
