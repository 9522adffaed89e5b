"""A Meshcat scene kept in this process instead of a server: the commands that build it,
packed as meshcat's own viewer reads them (``viewer.handle_command_bytearray``).

meshcat 0.3.2's ``Visualizer`` sends each command through a "window"; this one keeps the
latest command per path, so the scene can be handed to any page that connects (the teleop
console's WebSocket) or written as a standalone HTML file (meshcat's static page, built here
without its ZMQ server).
"""

from __future__ import annotations

import base64
import threading
from pathlib import Path

import meshcat
import umsgpack

MAIN_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
"""meshcat's browser viewer (three.js and the scene-command decoder), as its server serves it."""


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

    def static_html(self, title: str = "pinrate") -> str:
        """A standalone page: meshcat's viewer inlined and the scene's commands run in it."""
        commands = "\n".join(f'  "{base64.b64encode(packed).decode("ascii")}",' for packed in self.packed())
        return f"""<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>body {{ margin: 0; }} #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{MAIN_JS.read_text(encoding="utf-8")}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
const commands = [
{commands}
];
for (const text of commands) {{
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}}
</script>
</body>
</html>
"""


__all__ = ["MAIN_JS", "SceneCommands"]
