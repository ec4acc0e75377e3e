"""Export of the tables as raw float32 textures in the layout real-time engines read (Bruneton & Neyret 2008,
Sec. 6), with a JSON description.

Files (little-endian float32, no header, C order, channels interleaved per texel; channels sorted by
decreasing wavelength, so tables in the 3-wavelength mode (``tables="rgb"``) are R = 680 nm, G = 550 nm,
B = 440 nm; the default 16-wavelength tables export 16 channels):

* ``transmittance.raw`` - 2D, width ``n_mu`` x height ``n_r`` (row 0 at the ground).
* ``irradiance.raw`` - 2D, width ``n_mu_s`` x height ``n_r``: indirect irradiance on a horizontal surface.
* ``scattering.raw`` - the 4D table ``C* = S_R[L0] + S[L*] / P_R(nu_texel)`` packed into a 3D texture of width
  ``n_nu * n_mu_s``, height ``n_mu``, depth ``n_r``, with the ``nu`` slices side by side along x:
  ``x = i_nu * n_mu_s + i_mu_s`` (the paper's 32 x 128 x 256 layout, interpolated manually along nu).
* ``single_mie_scattering.raw`` - ``C_M = S_M[L0]`` in the same layout.
* ``single_rayleigh_scattering.raw`` and ``multiple_scattering.raw`` - ``S_R[L0]`` (no phase) and ``S[L*]``
  (phase included) apart, same layout: ``L = S_R P_R + C_M P_M + S[L*]`` avoids the bias of ``C*`` where a
  texel's ``nu`` is clamped (see :mod:`.tables`).
* ``scattering_rgba.raw`` (3 channels only) - the paper's 4-value texture: ``C*`` in RGB and the red
  channel of ``C_M`` in A; the other Mie channels follow from the proportionality rule of Sec. 4.
* ``atmosphere.json`` - sizes, coordinate mappings, constants, per-channel coefficients, the radiance formula
  and the matrix from channels to CIE XYZ.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..atmosphere.phase import rayleigh_phase
from ..errors import OutputError
from ..fileio import atomic_paths

if TYPE_CHECKING:  # pragma: no cover
    from .tables import PrecomputedAtmosphere

__all__ = ["export_tables"]

_MAPPINGS = {
    "index_convention": "texel i of an axis of size n sits at x = i / (n - 1); texture coordinate "
                        "u = (x * (n - 1) + 0.5) / n; values at the first and last texel are the ends of the range",
    "rho": "sqrt(r^2 - bottom_radius^2)",
    "H": "sqrt(top_radius^2 - bottom_radius^2)",
    "transmittance.x_r": "rho / H",
    "transmittance.x_mu": "(d - d_min) / (d_max - d_min), d = distance to the top boundary, d_min = top_radius - r, "
                          "d_max = rho + H (only rays that miss the ground)",
    "irradiance.x_r": "(r - bottom_radius) / (top_radius - bottom_radius)",
    "irradiance.x_mu_s": "(mu_s + 1) / 2",
    "scattering.x_r": "rho / H at the rows (row i at x_r = i / (n_r - 1)); within a cell of rows, for rays "
                      "that miss the ground, if row i lies above the ground and below 200 m altitude, the index "
                      "position is linear in r: "
                      "i + (r - r_i) / (r_(i+1) - r_i); "
                      "for rays that meet it rho / H",
    "scattering.x_mu": "rays that meet the ground: index (1 - (d - d_min) / (d_max - d_min)) * (n_mu / 2 - 1), "
                       "d = distance to the ground, "
                       "d_min = r - bottom_radius, d_max = rho; other rays: index n_mu / 2 + x * (n_mu / 2 - 1), "
                       "x = ((d - d_min) / (d_max - d_min) + theta / theta_h) / 2, d = distance to the top, "
                       "d_min = top_radius - r, d_max = rho + H, theta = acos(mu), theta_h = acos(-rho / r); "
                       "never interpolate across the two halves",
    "scattering.x_mu_s": "(max(1 - a / A, 0) / (1 + a) + 1 - acos(mu_s) / acos(mu_s_min)) / 2 "
                         "+ 0.1 (g - h), a = (d - d_min) / (d_max - d_min), d = distance from the "
                         "ground to the top along mu_s, d_min = top_radius - bottom_radius, d_max = H, "
                         "A = a at mu_s_min; e = 90 - acos(mu_s) [deg] the sun elevation, e_min its value at "
                         "mu_s_min, g = (G(e) - G(e_min)) / (G(90) - G(e_min)) with "
                         "G(e) = 1.5 (softplus((e + 9) / 1.5) - softplus((e - 1.5) / 1.5)), h the same with "
                         "G(e) = 12 (softplus((e - 14) / 12) - softplus((e - 40) / 12)), "
                         "softplus(z) = log(1 + exp(z))",
    "scattering.x_nu": "1 - phi / pi, cos(phi) = (nu - mu mu_s) / sqrt((1 - mu^2) (1 - mu_s^2)) (view-sun azimuth)",
    "radiance": "L = C* * P_R(nu) + C_M * P_M(nu) (paper), or without the C* bias at clamped texels "
                "L = S_R * P_R(nu) + C_M * P_M(nu) + S_multiple; P_R = 3 / (16 pi) (1 + nu^2); "
                "P_M = 3 / (8 pi) (1 - g^2) (1 + nu^2) / ((2 + g^2) (1 + g^2 - 2 g nu)^1.5)",
}


def _write_raw(path: Path, array: np.ndarray) -> dict[str, Any]:
    """Write ``array`` as little-endian float32 to ``path`` (a temporary of the export's group); its entry."""
    data = np.ascontiguousarray(array, dtype="<f4")
    with open(path, "wb") as fh:  # not ndarray.tofile, whose errors lose errno ("N requested and M written")
        fh.write(memoryview(data).cast("B"))
    return {"file": None, "dtype": "float32", "byte_order": "little", "shape": list(data.shape),
            "bytes": int(data.nbytes)}


#: The files of an export, in writing order (``scattering_rgba.raw`` only for 3-channel tables).
TEXTURES = ("transmittance", "irradiance", "scattering", "single_mie_scattering", "single_rayleigh_scattering",
            "multiple_scattering", "scattering_rgba")


def export_tables(atm: PrecomputedAtmosphere, folder: Path) -> Path:
    """Write the textures of ``atm`` and ``atmosphere.json`` into ``folder`` (created if missing), all together:
    every file is written to a temporary beside its target and the group is renamed into place only when all are
    written, so a failed or interrupted export (a full disk) leaves the folder as it was. Returns the JSON
    description's path."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output folder {folder}: {exc.strerror or exc}") from None
    order = np.argsort(-atm.wavelengths)
    names = [n for n in TEXTURES if n != "scattering_rgba" or order.size == 3]
    targets = [folder / f"{n}.raw" for n in names] + [folder / "atmosphere.json"]
    with atomic_paths(*targets) as temps:
        tmp = dict(zip(names + ["atmosphere.json"], temps, strict=True))
        _export(atm, order, tmp)
    return targets[-1]


def _export(atm: PrecomputedAtmosphere, order: np.ndarray, tmp: dict[str, Path]) -> None:
    t = atm.tables
    sizes = atm.sizes
    files: dict[str, Any] = {}
    n_r, n_mu, n_s, n_n = sizes.scattering_shape

    def packed(table: np.ndarray) -> np.ndarray:
        # (r, mu, mu_s, nu, c) -> (r, mu, nu, mu_s, c): x = i_nu * n_mu_s + i_mu_s
        return table[..., order].transpose(0, 1, 3, 2, 4).reshape(n_r, n_mu, n_n * n_s, order.size)

    def write(name: str, array: np.ndarray) -> dict[str, Any]:
        entry = _write_raw(tmp[name], array)
        entry["file"] = f"{name}.raw"
        files[name] = entry
        return entry

    write("transmittance", t["transmittance"][..., order]).update(
        width=sizes.transmittance_mu, height=sizes.transmittance_r, axes=["r", "mu", "channel"])
    write("irradiance", t["irradiance"][..., order]).update(
        width=sizes.irradiance_mu_s, height=sizes.irradiance_r, axes=["r", "mu_s", "channel"])
    from .kernels import texel_nu_kernel
    from .parallel import parallel_for
    from .sampling import lobe_weight, multiple_lobe_array

    nu = np.zeros(sizes.scattering_shape)
    p = atm.parameters
    parallel_for(texel_nu_kernel, n_r * n_mu, p.bottom_radius, p.top_radius, p.mu_s_min, nu)
    phase_r = rayleigh_phase(np.clip(nu, -1.0, 1.0))[..., None]
    # the table holds the multiple scattering divided by its lobe (.sampling.multiple_lobe); the paper's holds it whole
    multiple = t["multiple"] * multiple_lobe_array(np.clip(nu, -1.0, 1.0), lobe_weight(p))[..., None]
    combined = t["single_rayleigh"] + multiple / phase_r
    scat = packed(combined)
    mie = packed(t["single_mie"])
    write("scattering", scat)
    write("single_mie_scattering", mie)
    write("single_rayleigh_scattering", packed(t["single_rayleigh"]))
    write("multiple_scattering", packed(multiple))
    for name in ("scattering", "single_mie_scattering", "single_rayleigh_scattering", "multiple_scattering"):
        files[name].update(width=n_n * n_s, height=n_mu, depth=n_r, axes=["r", "mu", "nu * n_mu_s + mu_s", "channel"])
    if order.size == 3:
        rgba = np.concatenate([scat, mie[..., :1]], axis=-1)
        write("scattering_rgba", rgba).update(width=n_n * n_s, height=n_mu, depth=n_r,
                                              axes=["r", "mu", "nu * n_mu_s + mu_s", "C* RGB + C_M red"])
    wl = atm.wavelengths[order]  # channel order; the medium is evaluated at the (increasing) table wavelengths
    description = {
        "format": "skyscatter-bruneton-luts",
        "reference": "E. Bruneton, F. Neyret, Precomputed Atmospheric Scattering, EGSR 2008",
        "units": {"length": "m", "radiance": "W m^-2 sr^-1 nm^-1", "irradiance": "W m^-2 nm^-1"},
        "channels_wavelength_nm": [float(w) for w in wl],
        "orders": atm.orders,
        "sizes": {"transmittance": [sizes.transmittance_r, sizes.transmittance_mu],
                  "irradiance": [sizes.irradiance_r, sizes.irradiance_mu_s],
                  "scattering": [n_r, n_mu, n_s, n_n]},
        "textures": files,
        "atmosphere": {
            "bottom_radius": p.bottom_radius,
            "top_radius": p.top_radius,
            "mu_s_min": p.mu_s_min,
            "sun_angular_radius": p.sun_angular_radius,
            "mie_phase_g": p.mie_phase_g,
            "mie_phase_function": p.mie_phase_function,
            **{name: [float(v) for v in getattr(p, f"{name}_at")(atm.wavelengths)[order]]
               for name in ("solar_irradiance", "rayleigh_scattering", "mie_scattering", "mie_extinction",
                            "ozone_absorption", "ground_albedo")},
        },
        "mappings": _MAPPINGS,
        "channels_to_xyz": atm.xyz_matrix[:, order].tolist(),
        "parameters": p.to_dict(),
        "cache_key": atm.cache_key,
    }
    tmp["atmosphere.json"].write_text(json.dumps(description, indent=1), encoding="utf-8")
