"""A weather file made for the tests: a clear, a broken and an overcast day at a mid-latitude site.

Clear hours come from pvlib's SPECTRL2 (Bird & Riordan 1986, an independent clear-sky model) integrated over its
122 wavelengths, for a known aerosol optical depth and precipitable water; broken hours take the clear DNI times
0.4 and twice its DHI; overcast hours have no direct beam and a DHI of 0.35 GHI_clear. The EPW's sky cover is 0,
5 and 10 tenths, the precipitable water and aerosol fields are filled (the aerosol field with a value that
disagrees with the clear-hour truth, to show which one wins).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

SITE = {"latitude": 48.14, "longitude": 11.58, "timezone": 1.0, "elevation": 0.0}
#: Truth of the clear day: vertical AOD at 550 nm, Angstrom alpha, precipitable water [cm].
CLEAR_AOD = 0.15
ALPHA = 1.3
WATER = 1.5
#: The file's aerosol field (broadband, TMY convention), deliberately different from the truth.
FILE_AOD_BROADBAND = 0.05


def spectrl2_irradiance(zenith_deg: np.ndarray, day_of_year: np.ndarray, aod550: float = CLEAR_AOD,
                        water: float = WATER):
    """Broadband (DNI, DHI, GHI) [W m^-2] of SPECTRL2 for each hour (sea level, ozone 0.3 atm-cm, albedo 0.2)."""
    import pvlib

    out = np.zeros((zenith_deg.size, 3))
    beta500 = aod550 * (500.0 / 550.0) ** -ALPHA
    for i, (z, d) in enumerate(zip(zenith_deg, day_of_year, strict=True)):
        if z >= 89.0:
            continue
        am = pvlib.atmosphere.get_relative_airmass(z, model="kasten1966")
        s = pvlib.spectrum.spectrl2(apparent_zenith=z, aoi=z, surface_tilt=0.0, ground_albedo=0.2,
                                    surface_pressure=101325.0, relative_airmass=am, precipitable_water=water,
                                    ozone=0.3, aerosol_turbidity_500nm=beta500, dayofyear=int(d), alpha=ALPHA)
        wl = s["wavelength"]
        dni = np.trapezoid(s["dni"][:, 0], wl)
        dhi = np.trapezoid(s["dhi"][:, 0], wl)
        out[i] = dni, dhi, dhi + dni * np.cos(np.radians(z))
    return out


def write_epw(path: Path, *, days=((6, 20, "clear"), (6, 21, "broken"), (6, 22, "overcast")), year: int = 2023,
              site: dict | None = None, tweak=None) -> Path:
    """Write the EPW; ``tweak(records)`` may edit the list of field lists (bad-record tests)."""
    from skyscatter.sun.position import sun_position_unix

    site = SITE if site is None else site
    rows = []
    for month, day, kind in days:
        hours = np.arange(1, 25)
        start = np.datetime64(f"{year}-{month:02d}-{day:02d}T00:00").astype("datetime64[s]").astype(np.int64)
        unix = start + (hours - 0.5) * 3600.0 - site["timezone"] * 3600.0
        pos = sun_position_unix(np.radians(site["latitude"]), np.radians(site["longitude"]), unix, apparent=False)
        zen = np.degrees(np.asarray(pos.zenith))
        doy = (np.datetime64(f"{year}-{month:02d}-{day:02d}") - np.datetime64(f"{year}-01-01")).astype(int) + 1
        irr = spectrl2_irradiance(zen, np.full(24, doy))
        for h in range(24):
            dni, dhi, ghi = irr[h]
            cover = {"clear": 0, "broken": 5, "overcast": 10}[kind]
            if zen[h] >= 89.0:
                dni = dhi = ghi = 0.0
            elif kind == "broken":
                dni, dhi = 0.4 * dni, 2.0 * dhi
            elif kind == "overcast":
                dni, dhi = 0.0, 0.35 * ghi
            ghi = dhi + dni * max(np.cos(np.radians(zen[h])), 0.0)
            fields = [str(year), str(month), str(day), str(h + 1), "60", "?9?9?9?9E0", "18.0", "8.2", "60", "101325",
                      "9999", "9999", "9999", f"{ghi:.0f}", f"{dni:.0f}", f"{dhi:.0f}", "999999", "999999", "999999",
                      "9999", "180", "2.0", str(cover), str(cover), "9999", "99999", "9", "999999999",
                      f"{WATER * 10:.0f}", f"{FILE_AOD_BROADBAND:.3f}", "999", "99", "0.2", "999", "99"]
            rows.append(fields)
    if tweak is not None:
        tweak(rows)
    lines = [f"LOCATION,Synthville,BY,DEU,skyscatter tests,999999,{site['latitude']},{site['longitude']},"
             f"{site['timezone']},{site['elevation']}",
             "DESIGN CONDITIONS,0", "TYPICAL/EXTREME PERIODS,0", "GROUND TEMPERATURES,0",
             "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0", "COMMENTS 1,made by tests/weather_synth.py (SPECTRL2 clear day)",
             "COMMENTS 2,", f"DATA PERIODS,1,1,Data,Sunday,{days[0][0]}/{days[0][1]},{days[-1][0]}/{days[-1][1]}"]
    lines += [",".join(r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path
