"""The address the editor's in-process tests call it at: a loopback Host with a port, as a browser on
the user's machine sends (the app refuses any other Host: :mod:`mpeg4fa.guard`)."""
LOCAL = "http://127.0.0.1:8765"
