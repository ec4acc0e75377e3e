"""Reading the real-time textures back (:mod:`.export`), with every check the browser viewer also makes.

:func:`load_realtime` refuses, with :class:`~skyscatter.errors.FileFormatError` naming the file and saying what was
expected, a manifest that is not one (not JSON, another ``format``), a manifest of another version, a texture file
that is missing, and a file whose size is not the manifest's (truncated or padded).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import FileFormatError, InvalidParameterError
from .export import FORMATS, MANIFEST_FORMAT, MANIFEST_NAME, MANIFEST_VERSION, TEXTURE_NAMES

__all__ = ["RealtimeLuts", "load_realtime", "read_manifest"]


@dataclass(frozen=True)
class RealtimeLuts:
    """Textures read by :func:`load_realtime`: ``manifest`` (the JSON as a dict) and ``textures`` (name -> float32
    array, 2D (height, width, 4), 3D (depth, height, width, 4))."""

    manifest: dict[str, Any]
    textures: dict[str, NDArray[np.float32]]

    @property
    def constants(self) -> dict[str, Any]:
        return self.manifest["constants"]

    def mappings(self) -> dict[str, Any]:
        """The manifest's Python mapping functions, executed with its constants (a namespace dict)."""
        namespace: dict[str, Any] = dict(self.constants)
        exec(compile(self.manifest["mappings"]["python"], "<manifest mappings>", "exec"), namespace)  # noqa: S102
        return namespace


def read_manifest(folder: str | Path) -> dict[str, Any]:
    """The manifest of an export folder (or the manifest file itself), checked for format and version."""
    path = Path(folder)
    if path.is_dir():
        path = path / MANIFEST_NAME
    if not path.is_file():
        raise FileFormatError(f"{path}: no real-time manifest here (write one with 'skyscatter export-luts "
                              f"--formats rgba32f')")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"{path}: not a JSON manifest ({exc})") from None
    if not isinstance(manifest, dict) or manifest.get("format") != MANIFEST_FORMAT:
        raise FileFormatError(f"{path}: not a skyscatter real-time manifest (format "
                              f"{manifest.get('format') if isinstance(manifest, dict) else None!r}, expected "
                              f"{MANIFEST_FORMAT!r})")
    if manifest.get("version") != MANIFEST_VERSION:
        raise FileFormatError(f"{path}: manifest version {manifest.get('version')!r}, this skyscatter reads version "
                              f"{MANIFEST_VERSION} only; export the tables again with this version")
    return manifest


def load_realtime(folder: str | Path, *, fmt: str = "rgba32f") -> RealtimeLuts:
    """Read the textures of an export folder in format ``fmt`` (``rgba32f``, ``rgba16f`` or ``exr``) as float32.

    Raises
    ------
    FileFormatError
        Manifest missing, of another format or version; a texture file missing, or of the wrong size.
    InvalidParameterError
        An unknown ``fmt``.
    """
    if fmt not in FORMATS:
        raise InvalidParameterError(f"fmt must be one of {', '.join(FORMATS)}; got {fmt!r}")
    folder = Path(folder)
    manifest = read_manifest(folder)
    if folder.is_file():
        folder = folder.parent
    textures = {}
    for name in TEXTURE_NAMES:
        entry = manifest["textures"][name]
        files = entry.get("files", {})
        if fmt not in files:
            raise FileFormatError(f"{folder / MANIFEST_NAME}: texture {name} was not exported as {fmt} (exported: "
                                  f"{', '.join(files) or 'none'})")
        path = folder / files[fmt]["file"]
        if not path.is_file():
            raise FileFormatError(f"{path}: texture file missing (listed in {MANIFEST_NAME})")
        size = path.stat().st_size
        if size != files[fmt]["bytes"]:
            raise FileFormatError(f"{path}: {size} bytes, the manifest says {files[fmt]['bytes']} (truncated or "
                                  "damaged; export again)")
        shape = [entry["height"], entry["width"], 4]
        if entry["dimensions"] == 3:
            shape.insert(0, entry["depth"])
        textures[name] = _read(path, fmt, tuple(shape))
    return RealtimeLuts(manifest, textures)


def _read(path: Path, fmt: str, shape: tuple[int, ...]) -> NDArray[np.float32]:
    if fmt == "exr":
        import OpenEXR

        try:
            with OpenEXR.File(str(path)) as f:
                data = np.asarray(f.channels()["RGBA"].pixels, dtype=np.float32)
        except Exception as exc:  # OpenEXR raises RuntimeError/KeyError on damaged files
            raise FileFormatError(f"{path}: not a readable RGBA OpenEXR file ({exc})") from None
        if data.size != int(np.prod(shape)):
            raise FileFormatError(f"{path}: {data.shape} pixels, expected {shape}")
        return data.reshape(shape)
    data = np.fromfile(path, dtype="<f4" if fmt == "rgba32f" else "<f2")
    if data.size != int(np.prod(shape)):
        raise FileFormatError(f"{path}: {data.size} values, expected {int(np.prod(shape))} for {shape}")
    return data.reshape(shape).astype(np.float32)
