"""Convert the Hosek & Wilkie 2012/2013 reference headers (version 1.4a) into skyscatter's package data file.

Usage::

    python tools/generate_hosek_wilkie_data.py SKYMODEL_DIR [OUTPUT.npz]

``SKYMODEL_DIR`` holds the three data headers of the authors' reference implementation
(``ArHosekSkyModelData_Spectral.h``, ``ArHosekSkyModelData_CIEXYZ.h``, ``ArHosekSkyModelData_RGB.h``), for example
``src/ext/skymodel/`` of https://github.com/mmp/pbrt-v4 (the files are the authors' 1.4a release, BSD-3-Clause,
Copyright (c) 2012-2013 Lukas Hosek and Alexander Wilkie). The default output is
``src/skyscatter/data/hosek_wilkie_2013.npz``; the array layout is documented in ``docs/hosek_wilkie.md`` and in
:mod:`skyscatter.sky.hosek_wilkie`. The numbers are copied unchanged (parsed as float64); only the memory layout
changes from the headers' flat arrays to named N-d arrays.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np

N_ALBEDO, N_TURBIDITY, N_CONTROL, N_PARAMS = 2, 10, 6, 9
N_SEGMENTS, N_POLY = 45, 4
BANDS = list(range(320, 721, 40))
#: Version of the array layout written here (checked by the loader).
LAYOUT_VERSION = 1

_ARRAY = re.compile(r"double\s+(\w+)\s*\[\s*\]\s*=\s*\{(.*?)\}\s*;", re.S)
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def parse_header(path: Path) -> dict[str, np.ndarray]:
    """Every ``double NAME[] = { ... };`` array of a header (comments removed), as float64 arrays."""
    text = path.read_text(encoding="latin-1")
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    out = {}
    for name, body in _ARRAY.findall(text):
        if re.search(r"[A-Za-z_]\w*\s*,", body) and not _NUMBER.search(body):
            continue  # arrays of pointers
        out[name] = np.array([float(t) for t in _NUMBER.findall(body)], dtype=np.float64)
    return out


def _take(arrays: dict[str, np.ndarray], name: str, shape: tuple[int, ...]) -> np.ndarray:
    values = arrays[name]
    if values.size != int(np.prod(shape)):
        raise SystemExit(f"{name}: expected {int(np.prod(shape))} numbers, found {values.size}")
    return values.reshape(shape)


def convert(folder: Path) -> dict[str, np.ndarray]:
    spec = parse_header(folder / "ArHosekSkyModelData_Spectral.h")
    xyz = parse_header(folder / "ArHosekSkyModelData_CIEXYZ.h")
    rgb = parse_header(folder / "ArHosekSkyModelData_RGB.h")
    sky = (N_ALBEDO, N_TURBIDITY, N_CONTROL, N_PARAMS)
    rad = (N_ALBEDO, N_TURBIDITY, N_CONTROL)
    data = {
        "layout_version": np.array(LAYOUT_VERSION),
        "model_version": np.array("1.4a"),
        "wavelengths": np.array(BANDS, dtype=np.float64),
        "spectral_params": np.stack([_take(spec, f"dataset{b}", sky) for b in BANDS]),
        "spectral_radiance": np.stack([_take(spec, f"datasetRad{b}", rad) for b in BANDS]),
        "solar_polynomials": np.stack(
            [_take(spec, f"solarDataset{b}", (N_TURBIDITY, N_SEGMENTS, N_POLY)) for b in BANDS]
        ),
        "limb_darkening": np.stack([_take(spec, f"limbDarkeningDataset{b}", (6,)) for b in BANDS]),
        "xyz_params": np.stack([_take(xyz, f"datasetXYZ{c}", sky) for c in (1, 2, 3)]),
        "xyz_radiance": np.stack([_take(xyz, f"datasetXYZRad{c}", rad) for c in (1, 2, 3)]),
        "rgb_params": np.stack([_take(rgb, f"datasetRGB{c}", sky) for c in (1, 2, 3)]),
        "rgb_radiance": np.stack([_take(rgb, f"datasetRGBRad{c}", rad) for c in (1, 2, 3)]),
    }
    return data


def main(argv: list[str]) -> int:
    if len(argv) not in (2, 3):
        print(__doc__)
        return 2
    folder = Path(argv[1])
    out = Path(argv[2]) if len(argv) == 3 else (
        Path(__file__).resolve().parents[1] / "src" / "skyscatter" / "data" / "hosek_wilkie_2013.npz"
    )
    data = convert(folder)
    np.savez_compressed(out, **data)
    for k, v in data.items():
        print(f"{k:20s} {v.dtype} {v.shape}")
    print(f"wrote {out} ({out.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
