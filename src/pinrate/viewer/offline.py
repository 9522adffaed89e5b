"""A Meshcat scene kept in this process instead of a server: the commands that build it,
packed as meshcat's own viewer reads them (``viewer.handle_command_bytearray``).

meshcat 0.3.2's ``Visualizer`` sends each command through a "window"; this one keeps the
latest command per path, so the scene can be handed to any page that connects (the teleop
console's WebSocket) or written as a standalone HTML file (meshcat's static page, built here
without its ZMQ server).
"""

from __future__ import annotations

import base64
import html
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import IO

import meshcat
import numpy as np
import umsgpack

from ..files import replace_file

MAIN_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
"""meshcat's browser viewer (three.js and the scene-command decoder), as its server serves it."""

FLOAT32 = 0x17
"""meshcat's msgpack extension code of a Float32Array."""

PIECE = 3 * 2**16
"""Bytes of a packed command base64-encoded at a time (a multiple of 3) when a page is written,
and characters of the page written at a time."""


class SceneCommands:
    """A meshcat window that keeps the scene: objects, properties, transforms, animation."""

    def __init__(self) -> None:
        self._lock = threading.Lock()  # pages connect from the web thread
        self._objects: dict[str, bytes] = {}
        self._properties: dict[tuple[str, str], bytes] = {}
        self._transforms: dict[str, bytes] = {}
        self._animation: bytes | None = None

    def send(self, command: object) -> None:
        """Keep ``command`` (meshcat's SetObject, SetTransform, SetProperty, SetAnimation, Delete)."""
        lowered = command.lower()  # type: ignore[attr-defined]
        kind, path = lowered["type"], lowered["path"]
        packed = umsgpack.packb(lowered)
        with self._lock:
            if kind == "set_object":
                self._objects[path] = packed
            elif kind == "set_transform":
                self._transforms[path] = packed
            elif kind == "set_property":
                self._properties[(path, lowered["property"])] = packed
            elif kind == "set_animation":
                self._animation = packed
            elif kind == "delete":
                for table in (self._objects, self._transforms):
                    for key in [key for key in table if key == path or key.startswith(path + "/")]:
                        del table[key]
                for owner in [
                    owner for owner in self._properties if owner[0] == path or owner[0].startswith(path + "/")
                ]:
                    del self._properties[owner]

    def packed(self) -> list[bytes]:
        """The scene as packed commands, in the order a viewer must run them."""
        with self._lock:
            commands = [*self._objects.values(), *self._properties.values(), *self._transforms.values()]
            return commands if self._animation is None else [*commands, self._animation]

    def static_html(self, title: str = "pinrate", extra: Sequence[bytes] = ()) -> str:
        """A standalone page: meshcat's viewer inlined and the scene's commands run in it,
        then ``extra`` (packed commands, e.g. a replay's animation)."""
        return "".join(self.html_pieces(title, extra))

    def write_html(
        self, path: Path, title: str = "pinrate", extra: Sequence[bytes] = (), *, what: str = "replay file"
    ) -> Path:
        """:meth:`static_html` written to ``path`` piece by piece: no step of the write holds
        the GIL for long (a control loop in another thread keeps its period; one call
        encoding a whole 9 MB page held it for up to 50 ms). Whole or not at all
        (:func:`~pinrate.files.replace_file`): a write that fails leaves the file it was
        replacing as it was, and is an InputError naming ``what`` and the path."""

        def write(stream: IO[str]) -> None:
            for piece in self.html_pieces(title, extra):
                stream.write(piece)

        return replace_file(path, what, write, encoding="utf-8")

    def html_pieces(self, title: str = "pinrate", extra: Sequence[bytes] = ()) -> Iterator[str]:
        """The page of :meth:`static_html` in pieces of at most about :data:`PIECE` bytes."""
        yield f"""<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body {{ margin: 0; }} #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
"""
        script = MAIN_JS.read_text(encoding="utf-8")
        for start in range(0, len(script), PIECE):
            yield script[start : start + PIECE]
        yield """
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
const commands = [
"""
        for packed in [*self.packed(), *extra]:
            # Slices of a multiple of 3 bytes encode without padding, so they join as one text.
            slices = [packed[start : start + PIECE] for start in range(0, len(packed), PIECE)] or [b""]
            for index, part in enumerate(slices):
                last = index == len(slices) - 1
                yield f'  "{base64.b64encode(part).decode("ascii")}"' + (",\n" if last else " +\n")
        yield """];
for (const text of commands) {
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}
</script>
</body>
</html>
"""


class Animation:
    """meshcat's ``set_animation`` command for recorded poses, as flat arrays.

    ``paths``: the meshcat path of each animated node (``/meshcat/...``); ``poses`` (F, P, 7):
    each frame's position and quaternion ``[x y z qx qy qz qw]`` of each node (world frame,
    metres). Each node gets one ``.position`` and one ``.quaternion`` track whose ``times``
    (frame numbers; the clip's fps makes them seconds) and ``values`` are float32 arrays,
    which three.js's ``KeyframeTrack.parse`` takes as they are. meshcat's own Animation makes
    one dict per key instead: tens of thousands of objects, enough to wake the garbage
    collector for a full pass that holds the GIL for up to 30 ms (a control thread's tick).
    """

    def __init__(self, paths: Sequence[str], poses: np.ndarray, fps: float, *, repetitions: int = 1) -> None:
        self.paths = list(paths)
        self.poses = np.asarray(poses, dtype=np.float32).reshape(-1, len(self.paths), 7)
        self.fps = float(fps)
        self.repetitions = int(repetitions)

    def lower(self) -> list[dict[str, object]]:
        """The animations as meshcat's ``Animation.lower()`` gives them (what
        ``Visualizer.set_animation`` sends), one per node."""
        times = umsgpack.Ext(FLOAT32, np.arange(self.poses.shape[0], dtype=np.float32).tobytes())
        animations: list[dict[str, object]] = []
        for index, path in enumerate(self.paths):
            tracks = [
                {"name": f".{name}", "type": kind, "times": times, "values": umsgpack.Ext(FLOAT32, values.tobytes())}
                for name, kind, values in (
                    ("position", "vector3", np.ascontiguousarray(self.poses[:, index, :3])),
                    ("quaternion", "quaternion", np.ascontiguousarray(self.poses[:, index, 3:])),
                )
            ]
            animations.append({"path": path, "clip": {"fps": self.fps, "name": "default", "tracks": tracks}})
        return animations

    def packed(self) -> bytes:
        """The whole ``set_animation`` command, packed (playing, ``repetitions`` times)."""
        command = {
            "type": "set_animation",
            "animations": self.lower(),
            "options": {"play": True, "repetitions": self.repetitions},
            "path": "",
        }
        return umsgpack.packb(command)


__all__ = ["MAIN_JS", "Animation", "SceneCommands"]
