"""Write skyscatter's OPAC data files from the OPAC component files (Hess, Koepke & Schult 1998).

Usage: python tools/extract_opac_tables.py OPAC_DATA_DIR

OPAC_DATA_DIR holds the component output files of the OPAC package (``waso00`` ... ``suso99``: one file per
component and relative humidity, with the size distribution in the header, then per wavelength the extinction,
scattering and absorption coefficients for one particle per cm^3, single-scattering albedo, asymmetry
parameter and refractive index, then the volume phase function). The OPAC files read for skyscatter were those
redistributed in the repository aubema/illumina (Aerosol_optics/OPAC_data, commit cadadca). Only numbers are
taken: the size parameters and refractive indices (package data, src/skyscatter/data/opac_components.csv) and,
for the tests, OPAC's own Mie results (tests/data/opac_optics.csv, tests/data/opac_phase_550nm.csv).
"""

from __future__ import annotations

import sys
from pathlib import Path

#: OPAC component codes in the order of their numeric id in the data files.
COMPONENTS = ("inso", "waso", "soot", "ssam", "sscm", "minm", "miam", "micm", "mitr", "suso")
RH = (0, 50, 70, 80, 90, 95, 98, 99)
HEADER = """\
# OPAC aerosol components: log-normal size distributions and refractive indices (300-1250 nm).
# Source: M. Hess, P. Koepke, I. Schult (1998), 'Optical Properties of Aerosols and Clouds: The Software Package
# OPAC', Bull. Amer. Meteor. Soc. 79(5), 831-844, doi:10.1175/1520-0477(1998)079<0831:OPOAAC>2.0.CO;2, Table 1
# (components, dry mode radii, widths, radius limits) and the OPAC data files of each component and relative
# humidity (mode radius and radius limits of the wet particles, refractive index per wavelength), as
# redistributed in the repository aubema/illumina (Aerosol_optics/OPAC_data). Numbers only (facts); extracted
# by tools/extract_opac_tables.py.
# component_id: 1 inso (insoluble), 2 waso (water-soluble), 3 soot, 4 ssam (sea salt, accumulation mode),
# 5 sscm (sea salt, coarse mode), 6 minm (mineral, nucleation mode), 7 miam (mineral, accumulation mode),
# 8 micm (mineral, coarse mode), 9 mitr (mineral, transported), 10 suso (sulfate droplets).
# Columns: component id, relative humidity [%], smallest and largest radius [um], geometric standard deviation
# sigma [-], mode radius of the (wet) number distribution [um], dry mode radius [um], wavelength [nm], real
# part and imaginary part (>= 0, absorbing) of the refractive index.
component_id,rh_percent,r_min_um,r_max_um,sigma,r_mod_um,r_mod_dry_um,wavelength_nm,n_real,n_imag
"""


def parse(path: Path):
    lines = path.read_text().splitlines()
    head = {}
    for line in lines[:12]:
        if ":" in line:
            k, v = line.lstrip("# ").rsplit(":", 1)
            try:
                head[k.strip()] = float(v)
            except ValueError:
                head[k.strip()] = v.strip()
    optics, phase_wl, phase = [], None, []
    mode = None
    for line in lines:
        s = line.strip()
        if s.startswith("# wavelength ext.coef"):
            mode = "optics"
            continue
        if s.startswith("# volume phase function"):
            mode = "phase"
            continue
        if mode == "optics" and s.startswith("#") and len(s.split()) == 10:
            optics.append([float(x) for x in s[1:].split()])
        elif mode == "phase" and s.startswith("#") and "|" in s and "E" in s:
            phase_wl = [float(x) for x in s.split("|")[1].split()]
        elif mode == "phase" and not s.startswith("#") and s:
            phase.append([float(x) for x in s.split()])
    return head, optics, phase_wl, phase


def main(src: str) -> None:
    root = Path(__file__).resolve().parents[1]
    comp_rows, optic_rows, phase_cols = [], [], {}
    angles = None
    for cid, comp in enumerate(COMPONENTS, start=1):
        for rh in RH:
            f = Path(src) / f"{comp}{rh:02d}"
            if not f.exists():
                continue
            head, optics, phase_wl, phase = parse(f)
            for wl, ext, sca, _ab, ssa, g, _nor, nr, ni in optics:
                if 0.25 <= wl <= 1.25 + 1e-9:
                    r_lo, r_hi = head["minimum radius, [um]"], head["maximum radius, [um]"]
                    wet, dry = head["Rmod (wet), [um]"], head["Rmod (dry), [um]"]
                    comp_rows.append(f"{cid},{rh},{r_lo:.4g},{r_hi:.4g},{head['sigma']:.4g},{wet:.4g},{dry:.4g},"
                                     f"{wl * 1000:.6g},{nr:.6g},{-ni:.6g}")
                    optic_rows.append(f"{cid},{rh},{wl * 1000:.6g},{ext:.4e},{sca:.4e},{ssa:.4e},{g:.3f}")
            k = phase_wl.index(0.55)
            angles = [row[0] for row in phase]
            phase_cols[f"{comp}{rh:02d}"] = [row[1 + k] for row in phase]
    (root / "src/skyscatter/data/opac_components.csv").write_text(HEADER + "\n".join(comp_rows) + "\n")
    ref = root / "tests/data"
    ref.mkdir(exist_ok=True)
    (ref / "opac_optics.csv").write_text(
        "# OPAC's Mie results per component, relative humidity and wavelength for 1 particle per cm^3 (Hess et al.\n"
        "# 1998; OPAC data files as redistributed in aubema/illumina, Aerosol_optics/OPAC_data; numbers only).\n"
        "# Columns: component id (see src/skyscatter/data/opac_components.csv), RH [%], wavelength [nm], extinction\n"
        "# and scattering coefficients [1/km], single-scattering albedo, asymmetry parameter.\n"
        "component_id,rh_percent,wavelength_nm,ext_per_km,sca_per_km,ssa,g\n" + "\n".join(optic_rows) + "\n")
    names = list(phase_cols)
    rows = [",".join([f"{a:g}"] + [f"{phase_cols[n][i]:.4e}" for n in names]) for i, a in enumerate(angles)]
    (ref / "opac_phase_550nm.csv").write_text(
        "# OPAC's volume phase function at 550 nm [1/km, for 1 particle per cm^3] per component and relative\n"
        "# humidity (Hess et al. 1998; OPAC data files as redistributed in aubema/illumina; numbers only).\n"
        "angle_deg," + ",".join(names) + "\n" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
