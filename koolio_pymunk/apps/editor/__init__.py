"""The arena editor (``koolio-pm edit``): edit arena files in a pygame-ce window.

The editing model is apart from pygame so that it can be used and tested alone:

* :mod:`~koolio_pymunk.apps.editor.items` -- item paths (``walls[3]``, ``goals[1]``,
  ``end_of_world[0].zone[2]`` ...: the core validator's own names), reading and replacing
  the point or polygon an item path names, hit testing;
* :mod:`~koolio_pymunk.apps.editor.model` -- :class:`~koolio_pymunk.apps.editor.model.EditorModel`:
  the document, every editing operation as an undoable edit, snapping, validation with
  the core's validator, open / new / door-table import / save;
* :mod:`~koolio_pymunk.apps.editor.drive` -- the test drive (the core's ``KoolioEnv``);
* :mod:`~koolio_pymunk.apps.editor.script` -- scripted sessions (editor actions and posted
  events, one per line);
* :mod:`~koolio_pymunk.apps.editor.view` and :mod:`~koolio_pymunk.apps.editor.app` -- drawing and
  the window (pygame imported there only);
* :mod:`~koolio_pymunk.apps.editor.command` -- the ``koolio-pm edit`` command's flags, free of
  pygame (``tools/arena_editor.py`` runs the same command from a checkout).
"""
