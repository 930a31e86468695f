"""Rewards, events and episode end (paper §5.4.7).

The first rule that applies wins:

1. **goal**: the action was Stop and the front camera reads the goal Close
   (ends the episode);
2. **end_of_world**: the robot's centre is inside an end-of-world zone (ends the episode);
3. **bump**: any sonar reads Bump;
4. otherwise by the action: **stop**, **reverse**, **turn** (RotateLeft / RotateRight),
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

TERMS = ("goal", "end_of_world", "bump", "stop", "reverse", "turn", "forward")
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
    action: int, goal_close: bool, in_end_of_world: bool, bump: bool, rewards: RewardConfig
) -> Judgement:
    """Apply the paper's reward priority to one step."""
    if action == Action.STOP and goal_close:
        event = "goal"
    elif in_end_of_world:
        event = "end_of_world"
    elif bump:
        event = "bump"
    else:
        event = ACTION_TERMS[Action(action)]
    reward = float(getattr(rewards, event))
    terms = dict.fromkeys(TERMS, 0.0)
    terms[event] = reward
    return Judgement(event, reward, event in TERMINAL_EVENTS, terms)
