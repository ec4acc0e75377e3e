"""The made two-day EPW weather file of the tests (Munich-like site, June 20-21): header, records, day rows.

Shared by the EPW, sky matrix, CLI, Radiance and weather-check tests (a helper module, not a test module).
"""

import math

HEADER = [
    "LOCATION,Testville,BY,DEU,skyscatter test,999999,48.14,11.58,1.0,520.0",
    "DESIGN CONDITIONS,0",
    "TYPICAL/EXTREME PERIODS,0",
    "GROUND TEMPERATURES,0",
    "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
    "COMMENTS 1,written by tests/test_epw_skymatrix.py",
    "COMMENTS 2,",
    "DATA PERIODS,1,1,Data,Sunday, 6/20,6/21",
]


def record(month, day, hour, dni, dhi, dew=10.0, year=2023):
    """One 35-field EPW data line (unused fields carry the dictionary's missing codes)."""
    ghi = 9999 if 9999 in (dni, dhi) else dni + dhi
    fields = [year, month, day, hour, 60, "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9", 18.0, dew, 60,
              95500, 9999, 9999, 9999, ghi, dni, dhi, 999999, 999999, 999999, 9999, 180, 2.0, 5, 5, 9999,
              99999, 9, 999999999, 999, 0.999, 999, 99, 999, 999, 99]
    return ",".join(str(f) for f in fields)


def day_records():
    """Two June days: plausible clear-ish morning, cloudier afternoon, dark nights."""
    rows = []
    for day in (20, 21):
        for hour in range(1, 25):
            solar = math.sin(math.pi * (hour - 0.5 - 4.5) / 16) if 5 <= hour <= 21 else 0.0
            solar = max(solar, 0.0)
            dni = round(750 * solar**0.4) if hour < 15 else round(200 * solar)
            dhi = round(30 + 120 * solar) if solar > 0 else 0
            rows.append(record(6, day, hour, dni, dhi, dew=8.0 + hour / 4))
    return rows


def write_epw(path, header=None, rows=None):
    """Write an EPW file (default: HEADER and the two days of day_records) and return its path."""
    header = HEADER if header is None else header
    rows = day_records() if rows is None else rows
    path.write_text("\n".join(header + rows) + "\n", encoding="utf-8")
    return path
