"""Pixels and playback: the decode line's last layer.

``Renderer`` draws posed faces headless through OpenGL (EGL: a GPU, or Mesa's
llvmpipe on the CPU); ``play`` turns a decoded stream into an MP4 with its speech
or a PNG sequence; ``snapshot`` renders one frame; ``play_live`` paces frames to
the wall clock for live use; ``bake_texture`` colours the skin from photos.
Modules: ``context`` (EGL), ``camera``, ``materials``, ``scene`` (GL layout),
``renderer``, ``texture``, ``timing`` (presentation schedule), ``audio``,
``video`` (PyAV writers), ``realtime`` (pacing), ``window``, ``player``,
``lipsync`` (mouth vs speech energy).
"""
from mpeg4fa.render.audio import Audio, read_audio
from mpeg4fa.render.camera import Camera, frame_points
from mpeg4fa.render.errors import RenderError, RenderWarning
from mpeg4fa.render.materials import Materials
from mpeg4fa.render.player import PlayResult, play, play_live, snapshot
from mpeg4fa.render.renderer import Renderer

__all__ = ["Renderer", "Camera", "frame_points", "Materials", "play", "play_live", "snapshot", "PlayResult",
           "Audio", "read_audio", "RenderError", "RenderWarning"]
