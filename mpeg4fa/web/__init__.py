"""The face model editor's server side: a mesh being edited (:mod:`.edits`), a session with undo/redo
(:mod:`.session`) and a JSON API over both and the face engine (:mod:`.app`), served on 127.0.0.1."""
