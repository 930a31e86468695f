"""Rewards, events and episode end (paper §5.4.7).

The first rule that applies wins:

1. **goal**: the action was Stop and the front camera reads the goal Close
   (ends the episode);
2. **end_of_world**: the robot's centre is inside an end-of-world zone (ends the episode);
3. **robot_bump**: a sonar reads Bump from another robot (robots sharing an arena;
   ``rewards.robot_bump``, by default the wall bump's value);
4. **bump**: any sonar reads Bump;
5. otherwise by the action: **stop**, **reverse**, **turn** (RotateLeft / RotateRight),
   **forward**.

The reward is returned with its named terms (HighwayEnv style): every term is present in
``terms`` and exactly the winning one is non-zero (unless its configured value is 0).

>>> from koolio_pymunk.store.config import RewardConfig
>>> judge(0, goal_close=True, in_end_of_world=False, bump=True, rewards=RewardConfig())
Judgement(event='goal', reward=100.0, terminated=True)
>>> judge(3, goal_close=True, in_end_of_world=False, bump=False, rewards=RewardConfig()).event
'forward'
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..store.config import RewardConfig
from ..world.physics import Action

#: The named reward terms. ``robot_bump`` comes last so that the first seven keep the codes
#: they had before robots shared an arena (the compiled step's event codes are indices here).
TERMS = ("goal", "end_of_world", "bump", "stop", "reverse", "turn", "forward", "robot_bump")
ACTION_TERMS = {
    Action.STOP: "stop",
    Action.ROTATE_LEFT: "turn",
    Action.ROTATE_RIGHT: "turn",
    Action.FORWARD: "forward",
    Action.REVERSE: "reverse",
}
#: Events that end an episode (truncation by the step cap is reported separately).
TERMINAL_EVENTS = ("goal", "end_of_world")


@dataclass
class Judgement:
    """The outcome of one step: which rule won, its reward, and whether the episode ends."""

    event: str
    reward: float
    terminated: bool
    terms: dict[str, float] = field(default_factory=dict, repr=False)


def judge(
    action: int,
    goal_close: bool,
    in_end_of_world: bool,
    bump: bool,
    rewards: RewardConfig,
    robot_bump: bool = False,
) -> Judgement:
    """Apply the paper's reward priority to one step (``robot_bump``: a Bump read from
    another robot, in a shared arena)."""
    if action == Action.STOP and goal_close:
        event = "goal"
    elif in_end_of_world:
        event = "end_of_world"
    elif robot_bump:
        event = "robot_bump"
    elif bump:
        event = "bump"
    else:
        event = ACTION_TERMS[Action(action)]
    reward = rewards.value(event)
    terms = dict.fromkeys(TERMS, 0.0)
    terms[event] = reward
    return Judgement(event, reward, event in TERMINAL_EVENTS, terms)
