"""The editor's questions as pygame-gui windows: a line of text, yes / no, a file.

Each question is a :class:`Prompt` holding its pygame-gui window; the app
(:class:`~koolio_pymunk.apps.editor.app.EditorApp`) opens at most one at a time, routes the
widgets' events to it and calls ``on_done`` with the answer:

* :func:`text_prompt` -- a window with the question, a ``UITextEntryLine`` holding the
  proposed answer *selected* (typing or Backspace replaces it, as the highlight shows),
  OK and Cancel. Enter is OK, Esc is Cancel.
* :func:`confirm_prompt` -- a ``UIConfirmationDialog``; the key Y answers yes, N or Esc
  no (Enter does nothing: no file is overwritten by a stray Enter).
* :func:`file_prompt` -- a ``UIFileDialog`` (a folder's files, a path line, OK / Cancel);
  the path line is focused with all of it selected, so a path typed replaces it, and
  Enter on a file name is OK.
"""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pygame
import pygame_gui
from pygame_gui.elements import UIButton, UITextBox, UITextEntryLine, UIWindow
from pygame_gui.windows import UIConfirmationDialog, UIFileDialog

from .limits import MAX_TYPED


@dataclass
class Prompt:
    """An open question: ``kind`` is ``text``, ``confirm`` or ``file``."""

    kind: str
    label: str
    on_done: Callable[[str], None]
    window: Any
    entry: Any = None
    """The text line (``text`` and ``file`` questions)."""
    ok: Any = None
    cancel: Any = None

    @property
    def text(self) -> str:
        """The answer typed so far."""
        return self.entry.get_text() if self.entry is not None else ""

    def close(self) -> None:
        if self.window.alive():
            self.window.kill()


def _centred(canvas: pygame.Rect, w: int, h: int) -> pygame.Rect:
    w, h = min(w, canvas.w - 20), min(h, canvas.h - 20)
    return pygame.Rect(canvas.centerx - w // 2, canvas.centery - h // 2, w, h)


def select_all(manager: pygame_gui.UIManager, entry: UITextEntryLine) -> None:
    """Focus ``entry`` with its whole text selected (and the cursor at its end)."""
    manager.set_focus_set(entry)
    n = len(entry.get_text())
    entry.select_range = [0, n]
    entry.edit_position = n


def text_prompt(
    manager: pygame_gui.UIManager,
    canvas: pygame.Rect,
    title: str,
    label: str,
    default: str,
    on_done: Callable[[str], None],
) -> Prompt:
    """Ask for a line of text (at most :data:`~koolio_pymunk.apps.editor.limits.MAX_TYPED`
    characters); ``default`` is proposed, selected."""
    window = UIWindow(_centred(canvas, 520, 200), manager, window_display_title=title)
    w, h = window.get_container().get_size()
    UITextBox(html.escape(label), pygame.Rect(10, 8, w - 20, 62), manager, container=window)
    entry = UITextEntryLine(pygame.Rect(10, 76, w - 20, 32), manager, container=window)
    entry.set_text(default[:MAX_TYPED])
    entry.set_text_length_limit(MAX_TYPED)
    ok = UIButton(pygame.Rect(w - 220, h - 42, 100, 32), "OK", manager, container=window)
    cancel = UIButton(pygame.Rect(w - 110, h - 42, 100, 32), "Cancel", manager, container=window)
    select_all(manager, entry)
    return Prompt("text", label, on_done, window, entry, ok, cancel)


def confirm_prompt(
    manager: pygame_gui.UIManager,
    canvas: pygame.Rect,
    label: str,
    action: str,
    on_yes: Callable[[], None],
) -> Prompt:
    """Ask yes or no; ``action`` names the yes button (``Write anyway``, ``Quit``)."""
    window = UIConfirmationDialog(
        _centred(canvas, 520, 230),
        html.escape(label) + "<br><br>(Y: yes, N or Esc: no)",
        manager,
        window_title="Are you sure?",
        action_short_name=action,
    )
    return Prompt("confirm", label, lambda _: on_yes(), window)


def file_prompt(
    manager: pygame_gui.UIManager,
    canvas: pygame.Rect,
    title: str,
    path: str,
    existing: bool,
    on_done: Callable[[str], None],
) -> Prompt:
    """Ask for a file (``existing``: one that exists, to open)."""
    window = UIFileDialog(
        _centred(canvas, 640, 460),
        manager,
        window_title=title,
        initial_file_path=path or None,
        allow_existing_files_only=existing,
        allowed_suffixes={".yaml", ".yml"},
    )
    entry = window.file_path_text_line
    select_all(manager, entry)
    return Prompt("file", title, on_done, window, entry, window.ok_button, window.cancel_button)


def picked_file(prompt: Prompt) -> str | None:
    """The file a file question's path line names now (None: a folder, or nothing)."""
    current = getattr(prompt.window, "current_file_path", None)
    if current is None or current.is_dir():
        return None
    return str(current)
