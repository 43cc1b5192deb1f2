"""Show frames in a plain Tk window as they arrive.

Tk is in the standard library, so a preview needs no GUI toolkit beyond it; the
images go in as binary PPM, which ``tk.PhotoImage`` reads itself (no
``PIL.ImageTk``). Frames are pulled inside Tk's event loop with ``after``, so a
paced source such as :func:`mpeg4fa.render.realtime.live` sets the rate and the
window stays responsive between frames.
"""
from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterable, Iterator
from inspect import isgenerator
from typing import Any

import numpy as np

from mpeg4fa.render.errors import RenderError

__all__ = ["display_available", "ppm_bytes", "show"]


def display_available() -> bool:
    """Whether a Tk window can be opened here: checked by opening (and destroying) one."""
    if sys.platform not in ("win32", "darwin") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        return False
    try:
        import tkinter
    except ImportError:
        return False
    try:
        root = tkinter.Tk()
    except tkinter.TclError:
        return False
    root.destroy()
    return True


def ppm_bytes(image: Any) -> bytes:
    """An RGB uint8 (H, W, 3) image (alpha of (H, W, 4) dropped) as binary PPM, which Tk reads natively."""
    pixels = np.asarray(image)
    if pixels.ndim != 3 or pixels.shape[2] not in (3, 4) or pixels.dtype != np.uint8:
        raise RenderError(
            f"cannot show an image of shape {pixels.shape} and type {pixels.dtype}",
            where="window",
            hint="frames must be RGB uint8 arrays shaped (height, width, 3)",
        )
    if pixels.shape[0] == 0 or pixels.shape[1] == 0:
        raise RenderError(f"cannot show an empty image of shape {pixels.shape}", where="window")
    height, width = pixels.shape[:2]
    header = f"P6 {width} {height} 255\n".encode("ascii")
    return header + np.ascontiguousarray(pixels[:, :, :3]).tobytes()


def show(
    frames: Iterable[np.ndarray],
    *,
    title: str = "mpeg4fa",
    fps_hint: float | None = None,
    linger: float = 0.5,
) -> None:
    """Display frames in a window as they come; return when the window is closed or they run out.

    ``fps_hint`` paces a source that does not pace itself; leave it out for a
    live stream. Items with an ``image`` attribute (``LiveFrame``) show that
    image. After the last frame the window stays ``linger`` seconds. Closing the
    window stops consuming ``frames`` (and closes it if it is a generator).
    """
    if fps_hint is not None and not fps_hint > 0:
        raise ValueError(f"fps_hint must be > 0, not {fps_hint!r}")
    if not display_available():
        raise RenderError("no display to show a window on", where="window", hint="set DISPLAY or write frames with -o")
    import tkinter

    try:
        root = tkinter.Tk()
    except tkinter.TclError as exc:
        raise RenderError(f"cannot open a window: {exc}", where="window", hint="set DISPLAY or write frames with -o") from exc
    root.title(title)
    view = tkinter.Label(root, borderwidth=0, highlightthickness=0)
    view.pack()
    player = _Player(root, view, iter(frames), fps_hint, linger)
    root.protocol("WM_DELETE_WINDOW", player.close)
    root.after(0, player.step)
    try:
        root.mainloop()
    finally:
        player.finish()
    if player.error is not None:
        raise player.error


class _Player:
    """Pulls one frame per Tk ``after`` callback and puts it on the label."""

    def __init__(self, root: Any, view: Any, frames: Iterator[Any], fps_hint: float | None, linger: float) -> None:
        self.root, self.view, self.frames = root, view, frames
        self.interval = 1.0 / fps_hint if fps_hint else 0.0
        self.linger_ms = max(0, round(linger * 1000))
        self.closed = False
        self.exhausted = False
        self.shown = 0
        self.error: BaseException | None = None

    def step(self) -> None:
        if self.closed:
            return
        import tkinter

        started = time.monotonic()
        try:
            frame = next(self.frames)
        except StopIteration:
            self.exhausted = True
            self.root.after(self.linger_ms, self.close)
            return
        except BaseException as exc:  # raised again from show(), not lost in Tk's callback handler
            self.error = exc
            self.close()
            return
        try:
            photo = tkinter.PhotoImage(master=self.root, data=ppm_bytes(getattr(frame, "image", frame)), format="PPM")
        except Exception as exc:
            self.error = exc
            self.close()
            return
        self.view.configure(image=photo)
        self.view.image = photo  # Tk forgets an image Python no longer references
        self.shown += 1
        wait = self.interval - (time.monotonic() - started)
        self.root.after(max(1, round(wait * 1000)), self.step)

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        try:
            self.root.destroy()
        except Exception:
            pass

    def finish(self) -> None:
        self.close()
        if not self.exhausted:
            if isgenerator(self.frames):
                self.frames.close()
