"""The ground floor: what is kept on disk and how input is checked.

Configuration dataclasses and their validation (:mod:`.config`, :mod:`.realism_config`),
the Table 12 keyword layout (:mod:`.keyword`), safe YAML reading (:mod:`.yamlfile`),
atomic files and one-line file errors (:mod:`.files`), one writer per file
(:mod:`.locks`), the per-episode training log (:mod:`.episode_log`), the error classes
(:mod:`.errors`) and the optional ``[view]`` extra (:mod:`.extras`).

Imports nothing from the floors above (``world``, ``sensing``, ``task``, ``learning``,
``apps``); ``pyproject.toml``'s import-linter contract checks it.
"""
