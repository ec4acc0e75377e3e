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


def write_year_epw(path: Path, *, year: int = 2023, seed: int = 24, site: dict | None = None) -> Path:
    """A year of hours for benchmarks and the Monte Carlo comparison: each day clear (35 %), broken (35 %) or
    overcast (30 %), drawn with ``seed``; clear-sky irradiance from SPECTRL2 with a daily aerosol optical depth
    (log-normal around 0.12 at 550 nm) and a seasonal precipitable water (1-2.5 cm); broken and overcast days as
    in :func:`write_epw`. The file's water field holds the truth, its aerosol field a flat 0.1 (TMY style)."""
    import pvlib

    from skyscatter.sun.position import sun_position_unix

    site = SITE if site is None else site
    rng = np.random.default_rng(seed)
    start = np.datetime64(f"{year}-01-01T00:00").astype("datetime64[s]").astype(np.int64)
    n_days = 365
    hours = np.arange(n_days * 24)
    unix = start + (hours + 0.5) * 3600.0 - site["timezone"] * 3600.0
    pos = sun_position_unix(np.radians(site["latitude"]), np.radians(site["longitude"]), unix, apparent=False)
    zen = np.degrees(np.asarray(pos.zenith))
    doy = hours // 24 + 1
    kinds = rng.choice(3, size=n_days, p=[0.35, 0.35, 0.30])
    aod = np.exp(rng.normal(np.log(0.12), 0.4, size=n_days)).clip(0.02, 0.9)
    water = 1.75 - 0.75 * np.cos(2 * np.pi * (np.arange(n_days) - 15) / 365.0)
    day = hours // 24
    up = zen < 89.0
    dni = np.zeros(hours.size)
    dhi = np.zeros(hours.size)
    am = pvlib.atmosphere.get_relative_airmass(np.where(up, zen, 0.0), model="kasten1966")
    s = pvlib.spectrum.spectrl2(apparent_zenith=zen[up], aoi=zen[up], surface_tilt=0.0, ground_albedo=0.2,
                                surface_pressure=101325.0, relative_airmass=am[up],
                                precipitable_water=water[day[up]], ozone=0.3,
                                aerosol_turbidity_500nm=aod[day[up]] * (500 / 550) ** -ALPHA, dayofyear=doy[up],
                                alpha=ALPHA)
    wl = s["wavelength"]
    dni[up] = np.trapezoid(s["dni"], wl, axis=0)
    dhi[up] = np.trapezoid(s["dhi"], wl, axis=0)
    kind = kinds[day]
    ghi_clear = dhi + dni * np.maximum(np.cos(np.radians(zen)), 0.0)
    broken = kind == 1
    dni[broken] *= 0.4
    dhi[broken] *= 2.0
    over = kind == 2
    dni[over] = 0.0
    dhi[over] = 0.35 * ghi_clear[over]
    ghi = dhi + dni * np.maximum(np.cos(np.radians(zen)), 0.0)
    cover = np.array([0, 5, 10])[kind]
    rows = []
    dates = (np.datetime64(f"{year}-01-01") + np.arange(n_days)).astype(str)
    for i in hours:
        y, m, d = dates[day[i]].split("-")
        rows.append(",".join([y, str(int(m)), str(int(d)), str(i % 24 + 1), "60", "?9?9?9?9E0", "12.0", "6.0", "70",
                              "101325", "9999", "9999", "9999", f"{ghi[i]:.0f}", f"{dni[i]:.0f}", f"{dhi[i]:.0f}",
                              "999999", "999999", "999999", "9999", "180", "2.0", str(cover[i]), str(cover[i]), "9999",
                              "99999", "9", "999999999", f"{water[day[i]] * 10:.0f}", "0.100", "999", "99", "0.2",
                              "999", "99"]))
    head = [f"LOCATION,Synthville,BY,DEU,skyscatter benchmark,999999,{site['latitude']},{site['longitude']},"
            f"{site['timezone']},{site['elevation']}",
            "DESIGN CONDITIONS,0", "TYPICAL/EXTREME PERIODS,0", "GROUND TEMPERATURES,0",
            "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
            f"COMMENTS 1,made by tests/weather_synth.py write_year_epw (SPECTRL2 clear skies) seed {seed}",
            "COMMENTS 2,", "DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31"]
    path.write_text("\n".join(head + rows) + "\n")
    np.savez(path.with_suffix(".truth.npz"), aod=aod, water=water, kinds=kinds)
    return path
