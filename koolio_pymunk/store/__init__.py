"""The ground floor: what is kept on disk and how input is checked.

Configuration dataclasses and their validation (:mod:`.config`, :mod:`.realism_config`),
the Table 12 keyword layout (:mod:`.keyword`), safe YAML reading (:mod:`.yamlfile`),
atomic files and one-line file errors (:mod:`.files`), one writer per file
(:mod:`.locks`), the per-episode training log (:mod:`.episode_log`), the error classes
(:mod:`.errors`) and the optional ``[view]`` extra (:mod:`.extras`). The Q-table and its
files (:mod:`.qtable`, :mod:`.table_journal`, Dyna-Q's model section
:mod:`.dyna_model`), what a table is and who may use it (:mod:`.run_identity`), and a
run's files opened together (:mod:`.run_files`: the table and the log;
:mod:`.check_files`: the periodic checks' evaluations file and best table): a run is set
up on this floor, all its files checked before any is written, before the learners above
take the table.

Imports nothing from the floors above (``world``, ``sensing``, ``task``, ``learning``,
``apps``); ``pyproject.toml``'s import-linter contract checks it.
"""
