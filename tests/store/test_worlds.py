"""store/worlds.py: the world a run is in is named the same however its realism was
turned on (``--world``, ``--config``, settings without a file), and differently for
different realism."""

from __future__ import annotations

from pathlib import Path

from koolio_pymunk.store.config import PROFILE_DIR, load_config
from koolio_pymunk.store.worlds import world_label, world_name


def name(config=None, world=None, overrides=None) -> str:
    """What a run with ``--config config --world world`` (and ``overrides``) records."""
    own = load_config(config, overrides)
    cfg = load_config(config, overrides, world=world)
    return world_label(world_name(cfg, world, own.realism))


def test_the_ideal_world_and_worlds_laid_over_a_configuration_keep_their_names() -> None:
    assert name() == name("paper-memory") == name(overrides={"realism": {}}) == "ideal"
    assert name(world="koolio-real") == name("paper-memory", "koolio-real") == "koolio-real"
    assert name(world=PROFILE_DIR / "koolio-real-dr.yaml") == "koolio-real-dr.yaml"


def test_a_configuration_whose_realism_is_on_names_its_world() -> None:
    for profile in ("koolio-real", "koolio-real-dr"):
        assert name(profile) == name(world=profile) == profile
        realism = _plain(load_config(profile).realism)  # given as settings, not a file
        assert name(overrides={"realism": realism}) == profile
    assert name("koolio-real", "koolio-real") == "koolio-real"
    # koolio-real over koolio-real-dr keeps dr's randomization: the world is dr's
    assert name("koolio-real-dr", "koolio-real") == "koolio-real-dr"


def _plain(realism) -> dict:
    import dataclasses

    return dataclasses.asdict(realism)


def test_other_realism_is_named_by_its_content(tmp_path: Path) -> None:
    drifty = tmp_path / "drifty.yaml"
    drifty.write_text("realism: {motion: {drift_deg: 1.0}}\n")
    one = name(drifty)
    assert one.startswith("realism-") and len(one) == len("realism-") + 8
    assert one == name(overrides={"realism": {"motion": {"drift_deg": 1.0}}})  # same content
    (tmp_path / "other").mkdir()
    same = tmp_path / "other" / "drifty.yaml"  # the same name, other realism
    same.write_text("realism: {motion: {drift_deg: 2.0}}\n")
    assert name(same) not in (one, "ideal")
    assert name(drifty, "koolio-real") == "koolio-real"  # the world sets drift_deg itself
    wobbly = tmp_path / "wobbly.yaml"  # a randomization koolio-real keeps: a mix
    wobbly.write_text("realism: {randomize: {motion.drift_deg: [0.0, 2.0]}}\n")
    mixed = name(wobbly, "koolio-real")
    assert mixed.startswith("realism-") and mixed not in (name(wobbly), "koolio-real")
