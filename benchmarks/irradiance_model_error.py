"""The fit tables' systematic error in diffuse horizontal irradiance (DHI) against DISORT (issue 20).

The retrieval (``skyscatter.fit.atmosphere``) models DHI by the tables' ``ground_irradiance`` at its reduced
sizes (``FIT_SIZES``, 4 orders). This measures that model's error against DISORT (disortpp, plane-parallel, 32
streams, the phase table's exact Legendre moments; ``tests/disort_reference.py``) for airs with the analytic
aerosol (Cornette-Shanks) and with tabulated Mie phases (OPAC components and types, a fine + coarse mixture), at
sun zenith 20, 40, 60 deg, 400-830 nm, ground albedo 0.2. Each case's relative error ``e(lambda) = DHI_tables /
DHI_DISORT - 1`` is fitted by ``a + b ln(lambda / 550 nm)`` (least squares); the RMS of ``a`` and of ``b`` over
the cases of each phase kind are the sizes of ``fit.atmosphere.IRRADIANCE_MODEL_ERROR``.

    PYTHONPATH=src python benchmarks/irradiance_model_error.py
"""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import disort_diffuse_irradiance  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.atmosphere.aerosol_types import OpacAerosol  # noqa: E402
from skyscatter.conventions import direction_from_angles  # noqa: E402
from skyscatter.fit.atmosphere import FIT_SIZES  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402

WL = np.array([400.0, 440.0, 550.0, 670.0, 830.0])
SUN_ZENITH_DEG = (20.0, 40.0, 60.0)
H = AtmosphereParameters().thickness


def airs():
    out = {}
    for tau, g in ((0.1, 0.8), (0.25, 0.7), (0.5, 0.8)):
        out[f"analytic tau {tau} g {g}"] = ("analytic", AtmosphereParameters.from_aerosol_optical_depth(
            tau, 1.3, mie_phase_g=g, ground_albedo=0.2))
    mixtures = {"waso 0.25": (("waso", 0.25), ("sscm", 0.0)), "sscm 0.25": (("waso", 0.0), ("sscm", 0.25)),
                "waso 0.15 + sscm 0.10": (("waso", 0.15), ("sscm", 0.10)),
                "waso 0.05 + sscm 0.05": (("waso", 0.05), ("sscm", 0.05))}
    for name, members in mixtures.items():
        out[name] = ("table", AtmosphereParameters(ground_albedo=0.2,
                                                   aerosol=OpacAerosol.mixture(members, column_height=H)))
    for name in ("continental-average", "maritime-clean", "desert", "urban"):
        out[f"{name} 0.25"] = ("table", AtmosphereParameters(ground_albedo=0.2).with_aerosol_type(name, 0.25))
    return out


def main() -> None:
    x = np.log(WL / 550.0)
    design = np.stack([np.ones_like(x), x], axis=1)
    coef: dict[str, list[np.ndarray]] = {"analytic": [], "table": []}
    print("air | sun zenith | DHI tables / DISORT - 1 at " + ", ".join(f"{w:.0f}" for w in WL) + " nm [%] | a, b [%]")
    for name, (kind, air) in airs().items():
        atm = PrecomputedAtmosphere.compute(air, orders=4, wavelengths=WL, sizes=FIT_SIZES, progress=False)
        pos = np.array([0.0, 0.0, air.bottom_radius])
        esun = air.solar_irradiance_at(WL)
        for sz in SUN_ZENITH_DEG:
            sun = direction_from_angles(math.radians(sz), 0.0)
            dhi = atm.ground_irradiance(pos, np.array([0.0, 0.0, 1.0]), sun)[1]
            ref = esun * np.array([disort_diffuse_irradiance(air, w, math.radians(sz)) for w in WL])
            err = dhi / ref - 1.0
            ab = np.linalg.lstsq(design, err, rcond=None)[0]
            coef[kind].append(ab)
            print(f"{name} | {sz:.0f} | " + " ".join(f"{100 * e:+.1f}" for e in err)
                  + f" | {100 * ab[0]:+.1f}, {100 * ab[1]:+.1f}", flush=True)
    for kind, rows in coef.items():
        c = np.array(rows)
        rms = np.sqrt(np.mean(c ** 2, axis=0))
        print(f"{kind}: RMS a {100 * rms[0]:.1f} %, RMS b {100 * rms[1]:.1f} % per unit ln(lambda / 550 nm); "
              f"max |a| {100 * np.abs(c[:, 0]).max():.1f} %, max |b| {100 * np.abs(c[:, 1]).max():.1f} % "
              f"({len(rows)} cases)")


if __name__ == "__main__":
    main()
