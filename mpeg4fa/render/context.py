"""The OpenGL context: one headless EGL context per thread, created on first use.

EGL needs no display, so the same code runs on a desktop, a server's GPU or the
CPU (Mesa llvmpipe). Creating a context costs tens of milliseconds, so it is
shared by every renderer of a thread. A context is current on the thread that made it
only: a server's worker thread that bakes a texture gets its own.
"""
from __future__ import annotations

import threading
from importlib import resources

from mpeg4fa.render.errors import RenderError

_LOCAL = threading.local()

APT_HINT = ("install Mesa's EGL and GL (Debian: apt-get install libegl1 libgl1 libegl-mesa0 "
            "libgl1-mesa-dri), or run tools/dev.sh, which does")


def gl_context():
    """This thread's shared moderngl context (OpenGL >= 3.3 core, headless EGL)."""
    context = getattr(_LOCAL, "context", None)
    if context is None:
        try:
            import moderngl
        except ImportError as exc:  # pragma: no cover - a broken install
            raise RenderError(f"moderngl is not importable ({exc})", where="GL context",
                              hint="reinstall mpeg4fa with its dependencies") from None
        try:
            context = moderngl.create_standalone_context(backend="egl", require=330)
        except Exception as exc:  # moderngl/glcontext raise plain Exceptions on a missing library
            raise RenderError(f"cannot create a headless OpenGL context ({exc})", where="GL context",
                              hint=APT_HINT) from None
        _LOCAL.context, _LOCAL.programs = context, {}
    return context


def _with_defines(source: str, defines: tuple[str, ...]) -> str:
    first, _, rest = source.partition("\n")  # after the #version line
    return "\n".join([first, *(f"#define {d}" for d in defines), rest])


def program(name: str, defines: tuple[str, ...] = ()):
    """The shader program ``shaders/<name>.vert.glsl`` + ``.frag.glsl``, built once per thread's context.

    ``defines`` compile variants of one source (``#ifdef``): on llvmpipe every branch of a shader runs
    for every fragment, so parts drawn by few pixels (the eyes) get a variant of their own."""
    key = (name, tuple(defines))
    ctx = gl_context()
    prog = _LOCAL.programs.get(key)
    if prog is None:
        shaders = resources.files("mpeg4fa.render").joinpath("shaders")
        try:
            prog = ctx.program(
                vertex_shader=shaders.joinpath(f"{name}.vert.glsl").read_text(encoding="utf-8"),
                fragment_shader=_with_defines(shaders.joinpath(f"{name}.frag.glsl").read_text(encoding="utf-8"),
                                              tuple(defines)))
        except RenderError:
            raise
        except Exception as exc:  # a shader that does not compile is a bug of ours: say which
            raise RenderError(f"shader build failed: {exc}", where=f"shaders/{name}") from None
        _LOCAL.programs[key] = prog
    return prog


def describe_context() -> dict[str, str]:
    """Vendor, renderer and version strings: what is drawing (llvmpipe = CPU)."""
    info = gl_context().info
    return {key: str(info.get(key, "")) for key in ("GL_VENDOR", "GL_RENDERER", "GL_VERSION")}
