"""The editor's JSON API (FastAPI), over :mod:`.edits`, :mod:`.session` and the face engine.

Every fault answers ``{"error": one line, "where": the field or step}``: 400 (a body that is not
JSON or multipart), 422 (a request read but refused: a field out of its range, an edit that cannot
be made or that the model cannot hold, a file the readers refuse), 403 (not from the editor's own
page or a loopback address: :mod:`mpeg4fa.guard`), 404 (no such route) or 413 (upload too large, cut
as it streams). A refused request changes nothing: edits are checked before the session takes them,
so the session never holds a model it cannot answer with. Files are written only as plain names
inside ``out_dir``; nothing in a request is executed or opened as a path.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Literal, Union

import numpy as np
from fastapi import FastAPI, Form, HTTPException, Request, UploadFile
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, Response
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from mpeg4fa.atomic import atomic_outputs
from mpeg4fa.errors import MpegFaError
from mpeg4fa.guard import LocalOnly
from mpeg4fa.jsonio import JsonError, loads
from mpeg4fa.spec import FEATURE_POINTS, FULL_INTENSITY, N_FAPS
from mpeg4fa.web import edits, photos
from mpeg4fa.web.files import FORMATS, output_path, read_model, read_upload, save_model
from mpeg4fa.web.posing import held_in_range, pose_values, posed_vertices
from mpeg4fa.web.session import Session

UPLOAD_LIMIT = 64 * 1024 * 1024
MAX_BODY_JSON = 16 << 20
"""The largest JSON request body (an edit naming every vertex of a large mesh is some MB)."""
FORM_SLACK = 65536
"""Bytes a multipart request may carry beyond ``upload_limit`` (its boundaries and part headers)."""
MAX_INDEX = 2**62
"""The largest vertex or face index a request may name (any index past the mesh is refused by the edit itself)."""
STALE = "the mesh changed (an edit, load or upload) after it was calibrated"
HOST = "127.0.0.1"
STATIC = Path(__file__).with_name("static")
"""The editor page (``editor.html``), its ES modules (``js/``), style (``css/``) and vendored three.js."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


MAX_PIXEL = 1e6
"""The largest absolute pixel coordinate a photo point or box may have (a photo is some thousands wide)."""

Index = Annotated[int, Field(ge=0, le=MAX_INDEX)]
Finite = Annotated[float, Field(allow_inf_nan=False)]
Coordinate = Annotated[float, Field(ge=-edits.MAX_COORDINATE, le=edits.MAX_COORDINATE, allow_inf_nan=False)]
PixelCoordinate = Annotated[float, Field(ge=-MAX_PIXEL, le=MAX_PIXEL, allow_inf_nan=False)]
Xyz = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]


class DeleteFaces(_Strict):
    op: Literal["delete_faces"]
    faces: list[Index]


class DeleteVertices(_Strict):
    op: Literal["delete_vertices"]
    vertices: list[Index]


class FillHole(_Strict):
    op: Literal["fill_hole"]
    loop: list[Index]
    part: str | None = None


class MoveVertices(_Strict):
    op: Literal["move_vertices"]
    vertices: list[Index]
    positions: list[Xyz] | None = None
    delta: Xyz | None = None


class SplitPart(_Strict):
    op: Literal["split_part"]
    faces: list[Index]
    name: str


class RenamePart(_Strict):
    op: Literal["rename_part"]
    name: str
    to: str


class DeletePart(_Strict):
    op: Literal["delete_part"]
    name: str


class AssignPoint(_Strict):
    op: Literal["assign_point"]
    label: str
    vertex: Index


class ClearPoint(_Strict):
    op: Literal["clear_point"]
    label: str


class MirrorPoints(_Strict):
    op: Literal["mirror_points"]
    labels: list[str] | None = None
    overwrite: bool = False


Edit = Annotated[Union[DeleteFaces, DeleteVertices, FillHole, MoveVertices, SplitPart, RenamePart, DeletePart,
                       AssignPoint, ClearPoint, MirrorPoints], Field(discriminator="op")]


def _apply(e: BaseModel):
    match e:
        case DeleteFaces(): return lambda m: edits.delete_faces(m, e.faces)
        case DeleteVertices(): return lambda m: edits.delete_vertices(m, e.vertices)
        case FillHole(): return lambda m: edits.fill_hole(m, e.loop, e.part)
        case MoveVertices(): return lambda m: edits.move_vertices(m, e.vertices, e.positions, e.delta)
        case SplitPart(): return lambda m: edits.split_part(m, e.faces, e.name)
        case RenamePart(): return lambda m: edits.rename_part(m, e.name, e.to)
        case DeletePart(): return lambda m: edits.delete_part(m, e.name)
        case AssignPoint(): return lambda m: edits.assign_point(m, e.label, e.vertex)
        case ClearPoint(): return lambda m: edits.clear_point(m, e.label)
        case MirrorPoints(): return lambda m: edits.mirror_points(m, e.labels, overwrite=e.overwrite)
    raise AssertionError(e)  # pragma: no cover


class EditRequest(_Strict):
    edit: Edit


class LoadRequest(_Strict):
    source: Literal["head"]


class RegionRequest(_Strict):
    face: Index
    same_part: bool = False


class SaveRequest(_Strict):
    name: str = "model"
    required_points: list[str] | None = None


class ValidateRequest(_Strict):
    required_points: list[str] | None = None


class PoseRequest(_Strict):
    faps: dict[Annotated[int, Field(ge=3, le=N_FAPS)], Finite] = {}
    viseme: str | None = None
    expression: str | None = None
    intensity: Annotated[int, Field(ge=0, le=FULL_INTENSITY)] = FULL_INTENSITY


Pixel = Annotated[list[PixelCoordinate], Field(min_length=2, max_length=2)]


class BoxRequest(_Strict):
    view: Literal["front", "side"]
    box: Annotated[list[PixelCoordinate], Field(min_length=4, max_length=4)]
    dragged: dict[Literal["front", "side"], dict[str, Pixel]] = {}  # per view, the points put by hand (they stay put)


class FindRequest(_Strict):
    view: Literal["front", "side"] = "front"


class CalibrateRequest(_Strict):
    front: dict[str, Pixel]
    side: dict[str, Pixel]
    method: Literal["dffd", "rbf", "elastic"] = "dffd"


class ExportRequest(_Strict):
    name: str = "face"


def model_json(mesh: edits.EditMesh, session: Session) -> dict:
    """The mesh for three.js: flat positions and indices, each triangle's part, the placed points."""
    return {
        "source": mesh.source,
        "positions": np.round(mesh.vertices, 6).ravel().tolist(),
        "indices": mesh.triangles.ravel().tolist(),
        "parts": list(mesh.part_names),
        "triangle_parts": mesh.tri_part.tolist(),
        "points": mesh.points,
        "counts": {"vertices": len(mesh.vertices), "triangles": len(mesh.triangles)},
        "can_undo": bool(session.undo_stack), "can_redo": bool(session.redo_stack),
    }


def _error(status: int, error: str, where: str) -> JSONResponse:
    return JSONResponse({"error": error, "where": where}, status_code=status)


class _BodyError(HTTPException):
    """A JSON body the reader refused (FastAPI passes its HTTPException through the body parsing)."""

    def __init__(self, exc: JsonError) -> None:
        super().__init__(400, f"{exc.message} ({exc.hint})" if exc.hint else exc.message)
        self.where = exc.where or "body"


class _JsonRequest(Request):
    async def json(self):
        if not hasattr(self, "_json"):
            try:
                self._json = loads(await self.body(), "body", max_bytes=MAX_BODY_JSON, what="a request")
            except JsonError as exc:
                raise _BodyError(exc) from None
        return self._json


class _Route(APIRoute):
    """Routes whose JSON bodies are read by :func:`mpeg4fa.jsonio.loads` (nesting, size and numbers capped)."""

    def get_route_handler(self):
        handler = super().get_route_handler()

        async def route(request: Request):
            return await handler(_JsonRequest(request.scope, request.receive))
        return route


def create_app(model_path: str | os.PathLike | None = None, out_dir: str | os.PathLike = ".", *,
               head=None, upload_limit: int = UPLOAD_LIMIT) -> FastAPI:
    """The editor's app. ``model_path``: a mesh file to start with (else the head); ``head``: the
    :class:`~mpeg4fa.face.FaceModel` that ``load head`` gives and poses go through (default the generic head)."""
    out = Path(out_dir).resolve()
    app = FastAPI(title="mpeg4fa face model editor", docs_url=None, redoc_url=None, openapi_url=None)
    app.router.route_class = _Route
    app.add_middleware(LocalOnly, body_limit=upload_limit + FORM_SLACK)
    session = Session()
    state: dict = {"head": head, "cache": {}}

    def the_head():
        if state["head"] is None:
            from mpeg4fa.face import FaceModel
            state["head"] = FaceModel.default()
        return state["head"]

    app.state.session, app.state.out_dir = session, out
    if model_path is not None:
        path = Path(model_path)
        session.load(read_model(path))

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError):
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first.get("loc", ()) if p != "body") or "body"
        if first.get("type") == "json_invalid":
            return _error(400, f"malformed JSON: {first.get('ctx', {}).get('error', first.get('msg'))}", "body")
        return _error(422, f"{first.get('msg', 'invalid request')}", where)

    @app.exception_handler(MpegFaError)
    async def _failed(request: Request, exc: MpegFaError):
        text = f"{exc.message} ({exc.hint})" if exc.hint else exc.message
        return _error(422, text, exc.where or request.url.path)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        if isinstance(exc, _BodyError):
            return _error(exc.status_code, str(exc.detail), exc.where)
        return _error(exc.status_code, str(exc.detail).lower(), request.url.path)

    @app.get("/", response_class=HTMLResponse)
    def index():
        return (STATIC / "editor.html").read_text(encoding="utf-8")

    app.mount("/static", StaticFiles(directory=STATIC), name="static")

    @app.get("/api/model")
    def get_model():
        return model_json(session.require(), session)

    @app.get("/api/feature-points")
    def feature_points():
        return {"points": [{"label": f.label, "group": f.group, "description": f.description,
                            "side": f.side, "mirror": f.mirror} for f in FEATURE_POINTS]}

    @app.post("/api/load")
    def load(req: LoadRequest):
        session.load(edits.from_head(the_head().mesh))
        return model_json(session.mesh, session)

    @app.post("/api/upload")
    async def upload(request: Request, file: list[UploadFile]):
        """One model file and its companions (multipart ``file``, repeated): see :func:`read_upload`."""
        files, total = [], 0
        for part in file:
            data = await part.read(upload_limit + 1 - total)
            total += len(data)
            if total > upload_limit:
                return _error(413, f"upload larger than {upload_limit} bytes (all files together)", "file")
            files.append((part.filename or "upload", data))
        session.load(read_upload(files))
        return model_json(session.mesh, session)

    @app.post("/api/edit")
    def edit(req: EditRequest):
        return model_json(session.apply(_apply(req.edit)), session)

    @app.post("/api/undo")
    def undo():
        return model_json(session.undo(), session)

    @app.post("/api/redo")
    def redo():
        return model_json(session.redo(), session)

    @app.post("/api/region")
    def region(req: RegionRequest):
        return {"faces": edits.connected_region(session.require(), req.face, same_part=req.same_part).tolist()}

    @app.get("/api/fapu")
    def get_fapu():
        return {"fapu": edits.fapu(session.require()).as_dict()}

    @app.post("/api/validate")
    def check(req: ValidateRequest):
        problems = edits.validate(session.require(), req.required_points)
        return {"ok": not problems, "problems": problems}

    @app.post("/api/save")
    def save(req: SaveRequest):
        paths = save_model(session.require(), out, req.name, req.required_points)
        return {"files": [p.name for p in paths], "folder": str(out)}

    @app.post("/api/pose")
    def pose(req: PoseRequest):
        faps, said = held_in_range(req.faps)  # what was clamped goes back to the page, not to the console
        values = pose_values(faps, req.viseme, req.expression, req.intensity)
        v = posed_vertices(session.require(), the_head(), values, state["cache"])
        return {"positions": np.round(v, 6).ravel().tolist(), "warnings": said}

    # -- photo calibration (issue 17 item 4; the pure steps are in .photos) ---------------------------

    def need_photos() -> dict:
        if "photos" not in state:
            raise edits.EditError("no photos loaded", where="photos", hint="POST /api/photos first (front and side)")
        return state["photos"]

    def still_current(ph: dict) -> bool:
        """A calibration belongs to the mesh it was made on (edits make new meshes): cleared once that changes."""
        if "calibrated" in ph and ph["calibrated"]["mesh"] is not session.mesh:
            ph.pop("calibrated")
            ph.pop("texture", None)
            ph["cleared"] = STALE
        return "calibrated" in ph

    def need_calibration() -> dict:
        ph = need_photos()
        if not still_current(ph):
            if ph.get("cleared"):
                raise edits.EditError(f"the calibration was cleared: {ph['cleared']}", where="calibrate",
                                      hint="calibrate again (POST /api/calibrate)")
            raise edits.EditError("nothing calibrated yet", where="calibrate", hint="POST /api/calibrate first")
        return ph

    @app.get("/api/photos")
    def photo_state():
        ph = state.get("photos")
        if ph is None:
            return {"loaded": False, "calibrated": False, "cleared": None}
        current = still_current(ph)
        return {"loaded": True, "calibrated": current, "cleared": None if current else ph.get("cleared"),
                "front": {"size": list(ph["sizes"]["front"])}, "side": {"size": list(ph["sizes"]["side"])},
                "side_view": ph["side_view"], "guess": ph["guess"]}

    @app.post("/api/photos")
    async def load_photos(front: UploadFile, side: UploadFile,
                          side_view: Annotated[Literal["left", "right"], Form()] = "left"):
        images = {}
        for key, f in (("front", front), ("side", side)):
            data = await f.read(upload_limit + 1)
            if len(data) > upload_limit:
                return _error(413, f"upload larger than {upload_limit} bytes", key)
            images[key] = photos.decode_photo(data, key)
        sizes = {k: (int(im.shape[1]), int(im.shape[0])) for k, im in images.items()}
        placed = photos.guess(the_head().mesh, sizes, side_view, photos.first_boxes(the_head().mesh, images, side_view))
        state["photos"] = {"images": images, "sizes": sizes, "side_view": side_view, "guess": placed,
                           "dragged": {"front": {}, "side": {}}}
        return {"front": {"size": list(sizes["front"])}, "side": {"size": list(sizes["side"])},
                "side_view": side_view, "guess": placed}

    @app.post("/api/photos/box")
    def photo_box(req: BoxRequest):
        ph = need_photos()
        box = photos.check_box(req.box, ph["sizes"][req.view], "box")
        boxes = dict(ph["guess"]["box"], **{req.view: box})
        dragged = {**ph["dragged"], **{view: dict(points) for view, points in req.dragged.items()}}
        ph["guess"] = photos.guess(the_head().mesh, ph["sizes"], ph["side_view"], boxes, dragged)
        ph["dragged"] = dragged
        return {"guess": ph["guess"]}

    @app.post("/api/photos/find")
    def photo_find(req: FindRequest):
        """The face found in a loaded photo: its points placed (they count as put by hand: a later box drag
        leaves them), the box fitted to them so that the points not found follow."""
        ph = need_photos()
        view = "front" if req.view == "front" else ph["side_view"]
        found, box = photos.find_points(the_head().mesh, ph["images"][req.view], view, req.view)
        boxes = dict(ph["guess"]["box"], **{req.view: [round(v, 3) for v in box]})
        dragged = {**ph["dragged"], req.view: {**ph["dragged"][req.view], **found}}
        ph["guess"] = photos.guess(the_head().mesh, ph["sizes"], ph["side_view"], boxes, dragged)
        ph["dragged"] = dragged
        return {"guess": ph["guess"], "found": sorted(found)}

    @app.post("/api/calibrate")
    def calibrate(req: CalibrateRequest):
        ph = need_photos()
        mesh, head = session.require(), the_head()
        if (mesh.origin is None or len(mesh.origin) != len(mesh.vertices) or not len(mesh.origin)
                or (mesh.origin < 0).any() or mesh.origin.max() >= head.mesh.n_vertices):
            raise edits.EditError("photo calibration works on the head only; this mesh is not the head's",
                                  where="calibrate", hint="load the head (POST /api/load) first")
        face, targets, report = photos.calibrate_from_photos(head, req.front, req.side, ph["side_view"], req.method)
        ph["calibrated"] = {"face": face, "front": dict(req.front), "side": dict(req.side), "mesh": mesh}
        ph.pop("texture", None)
        ph.pop("cleared", None)
        skin = mesh.part_names.index("skin") if "skin" in mesh.part_names else -1
        return {"positions": np.round(face.mesh.vertices[mesh.origin], 6).ravel().tolist(),
                "points": {k: np.round(face.mesh.fp(k), 6).tolist() for k in targets}, "report": report,
                "skin": photos.skin_texture_mapping(head.mesh, mesh.origin, mesh.triangles),
                "other_indices": mesh.triangles[mesh.tri_part != skin].ravel().tolist()}

    def baked() -> np.ndarray:
        ph = need_calibration()
        if "texture" not in ph:
            c = ph["calibrated"]
            ph["texture"] = photos.bake(c["face"], ph["images"], c["front"], c["side"], ph["side_view"])
        return ph["texture"]

    # The bake draws with GL, whose context works only on the thread that made it: these two routes are
    # async, so they run on the event loop's thread (uvicorn's main thread), never in the worker pool.
    @app.get("/api/texture-preview")
    async def texture_preview():
        return Response(photos.encode_png(baked()), media_type="image/png")

    @app.post("/api/export")
    async def export(req: ExportRequest):
        from mpeg4fa.fdp import save_fdp

        ph = need_calibration()
        paths = [output_path(out, f"{req.name}{s}") for s in (".fdp", ".texture.png")]
        c = ph["calibrated"]
        fdp = photos.photo_fdp(c["front"], c["side"], ph["side_view"], ph["images"]["front"], req.name)
        png = photos.encode_png(baked())
        out.mkdir(parents=True, exist_ok=True)
        with atomic_outputs(*paths) as tmps:
            save_fdp(fdp, tmps[0])
            tmps[1].write_bytes(png)
        return {"files": [p.name for p in paths], "folder": str(out)}

    return app


__all__ = ["create_app", "HOST", "FORMATS"]
