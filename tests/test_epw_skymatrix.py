"""EPW reading (good and malformed files) and the annual sky matrix."""

import math

import numpy as np
import pytest

import skyscatter
from epw_records import HEADER, day_records, record
from skyscatter.epw import read_epw
from skyscatter.errors import FileFormatError, InvalidParameterError
from skyscatter.patches import patch_luminance, patch_scheme
from skyscatter.sky.perez import PerezSky


def test_read_good_file(epw_file):
    epw = read_epw(epw_file)
    loc = epw.location
    assert (loc.city, loc.country, loc.latitude_deg, loc.longitude_deg, loc.timezone_hours, loc.elevation) == (
        "Testville", "DEU", 48.14, 11.58, 1.0, 520.0)
    assert loc.latitude == pytest.approx(math.radians(48.14))
    assert len(epw) == 48
    assert epw.hour[0] == 1 and epw.hour[-1] == 24
    times = epw.times()
    assert str(times[0]) == "2023-06-20 00:30:00+01:00"  # middle of the hour ending 01:00 local standard time
    assert str(times[-1]) == "2023-06-21 23:30:00+01:00"
    assert epw.day_of_year[0] == 171
    assert epw.line_numbers[0] == 9
    assert epw.dew_point[0] == pytest.approx(8.25)
    assert epw.direct_normal_irradiance[12] > 0 and epw.diffuse_horizontal_irradiance[0] == 0


def _write(tmp_path, lines):
    path = tmp_path / "bad.epw"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _replace_record(i, row):
    return lambda h, r: (h, r[:i] + [row] + r[i + 1 :])


def _edit_first(old, new):
    return lambda h, r: (h, [r[0].replace(old, new, 1)] + r[1:])


@pytest.mark.parametrize(
    "mutate,message",
    [
        (lambda h, r: (["NOT A LOCATION"] + h[1:], r), r"line 1: an EPW file starts with a LOCATION line"),
        (lambda h, r: ([h[0]] + h[2:], r), r"line 2: header line 2 should start with 'DESIGN CONDITIONS'"),
        (lambda h, r: (["LOCATION,A,B,C"] + h[1:], r), r"line 1: LOCATION needs 10 fields"),
        (lambda h, r: ([h[0].replace("48.14", "95.0")] + h[1:], r), r"line 1: latitude 95 deg is outside"),
        (lambda h, r: ([h[0].replace("11.58", "east")] + h[1:], r), r"line 1: longitude 'east' is not a number"),
        (lambda h, r: (h[:7] + ["DATA PERIODS,1,4,Data,Sunday, 6/20,6/21"], r),
         r"line 9: 2023-06-20 hour 1 holds 1 record\(s\), but the DATA PERIODS header \(line 8\) declares 4"),
        (lambda h, r: (h[:7] + ["DATA PERIODS,1,7,Data,Sunday, 6/20,6/21"], r), r"line 8: .*7 records per hour"),
        # issue 12, item 1: the same hour twice, and a 4-per-hour file whose header declares 1
        (lambda h, r: (h, r[:6] + [r[5]] + r[6:]), r"line 15: 2023-06-20 hour 6 holds 2 records, but .* declares 1"),
        (lambda h, r: (h, r + [r[3]]), r"line 57: 2023-06-20 hour 4 appears again \(first at line 12\)"),
        (lambda h, r: (h, [x for x in r[:3] for _ in range(4)] + r[3:]), r"line 10: 2023-06-20 hour 1 holds 4"),
        # issue 12, item 7: years outside the time stamps' range
        (_edit_first("2023,6,20,1,", "0,6,20,1,"), r"line 9: year 0 is outside 1678-2261"),
        (_edit_first("2023,6,20,1,", "-5,6,20,1,"), r"line 9: year -5 is outside"),
        (_edit_first("2023,6,20,1,", "99999,6,20,1,"), r"line 9: year 99999 is outside"),
        (_edit_first("2023,6,20,1,", "1e20,6,20,1,"), r"line 9: year 1e20 is outside"),
        (lambda h, r: (h, r[:5] + [r[5] + ",7"] + r[6:]), r"line 14: a data record has 35 .* found 36"),
        (lambda h, r: (h, r[:3] + [",".join(r[3].split(",")[:-2])] + r[4:]), r"line 12: .*found 33"),
        (lambda h, r: (h, r[:2] + [r[2].replace(",18.0,", ",hot,", 1)] + r[3:]), r"line 11: dry bulb .*'hot' is not"),
        (_edit_first("2023,6,20,1,", "2023,13,20,1,"), r"line 9: month 13 is outside 1-12"),
        (_edit_first("2023,6,20,1,", "2023,6,31,1,"), r"line 9: 2023-06-31 is not a date"),
        (_edit_first("2023,6,20,1,", "2023,6,20,0,"), r"line 9: hour 0 is outside 1-24"),
        (_replace_record(12, record(6, 20, 13, -5, 100)), r"line 21: direct normal radiation -5 Wh m\^-2 is outside"),
        (_replace_record(12, record(6, 20, 13, 500, 100, dew=85)), r"line 21: dew point temperature 85"),
        (lambda h, r: (h, []), r"has 8 lines"),
    ],
)
def test_malformed_files_name_the_line(tmp_path, mutate, message):
    header, rows = mutate(list(HEADER), day_records())
    with pytest.raises(FileFormatError, match=message):
        read_epw(_write(tmp_path, header + rows))


def test_missing_file(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        read_epw(tmp_path / "nope.epw")


def test_skymatrix_missing_radiation_names_the_line(tmp_path):
    rows = day_records()
    rows[12] = record(6, 20, 13, 9999, 100)
    with pytest.raises(FileFormatError, match=r"line 21: direct normal radiation is missing"):
        skyscatter.skymatrix(_write(tmp_path, HEADER + rows))


def test_skymatrix_shape_zero_nights_and_scale(epw_file):
    m = skyscatter.skymatrix(epw_file, scheme="reinhart2")
    assert m.shape == (48, 577)
    assert np.all(np.isfinite(m.luminance)) and np.all(m.luminance >= 0)
    dark = m.diffuse_illuminance == 0
    assert np.all(m.luminance[dark] == 0) and dark.sum() >= 10
    lit = ~dark
    # the patch sum (centre cosine, mean luminance) reproduces the hour's diffuse illuminance to 1 %
    np.testing.assert_allclose(m.horizontal_illuminance()[lit], m.diffuse_illuminance[lit], rtol=1e-2)
    assert np.all((m.epsilon[lit] >= 1) & (m.epsilon[lit] <= 11.9))


def test_skymatrix_rows_match_the_perez_sky_class(epw_file):
    """The compiled hourly kernel against PerezSky + patch_luminance (numpy, finer normalisation rule)."""
    epw = read_epw(epw_file)
    m = skyscatter.skymatrix(epw, scheme="tregenza", samples=3)
    for h in (9, 12, 17, 33):
        assert m.sun_zenith[h] < math.pi / 2
        sky = PerezSky(m.sun_zenith[h], m.sun_azimuth[h], direct_normal_irradiance=epw.direct_normal_irradiance[h],
                       diffuse_horizontal_irradiance=epw.diffuse_horizontal_irradiance[h],
                       day_of_year=int(epw.day_of_year[h]), dew_point=epw.dew_point[h])
        assert m.diffuse_illuminance[h] == pytest.approx(sky.diffuse_illuminance, rel=1e-12)
        np.testing.assert_allclose(m.luminance[h], patch_luminance(sky, "tregenza", samples=3), rtol=1e-3)


def test_quadrature_by_moments_equals_the_per_node_sum(monkeypatch):
    """The normalisation term by term (row moments for 1 and cos^2 gamma, exp(d gamma) per node) against the
    per-node sum of max(0, I) (the path every sky took before), on 300 random Perez skies of the 1993 table's
    range; and skies whose indicatrix can be negative take the per-node path (lower bound <= 0)."""
    from skyscatter import sky_matrix as sm
    from skyscatter.conventions import direction_from_angles

    rng = np.random.default_rng(3)
    n = 300
    coeffs = np.column_stack([rng.uniform(-1.8, 1.0, n), rng.uniform(-1.1, -0.03, n), rng.uniform(0.03, 23.0, n),
                              rng.uniform(-6.4, -0.07, n), rng.uniform(-0.14, 1.4, n)])
    sun = direction_from_angles(rng.uniform(0.05, math.pi / 2, n), rng.uniform(0.0, 2 * math.pi, n))
    scale = rng.uniform(1e3, 5e4, n)
    scheme = patch_scheme("reinhart2")
    assert sm._perez_positive(coeffs).all()
    for samples in (1, 2):
        fast = sm.perez_patch_luminance(coeffs, sun, scale, scheme, samples=samples)
        with monkeypatch.context() as mp:
            mp.setattr(sm, "_perez_positive", lambda c: np.zeros(c.shape[0], dtype=bool))
            slow = sm.perez_patch_luminance(coeffs, sun, scale, scheme, samples=samples)
        np.testing.assert_allclose(fast, slow, rtol=1e-13, atol=0.0)
    # an indicatrix that dips below zero (e < -1 near gamma = 90 deg): not positive, so the per-node max(0, I)
    neg = np.array([[-1.0, -0.3, 0.05, -3.0, -1.2]])
    assert not sm._perez_positive(neg).any()
    gamma = np.linspace(0.0, math.pi, 181)
    assert np.min(1.0 + neg[0, 2] * np.exp(neg[0, 3] * gamma) + neg[0, 4] * np.cos(gamma) ** 2) < 0.0


def test_skymatrix_sun_spread_over_the_four_nearest_patches(epw_file):
    """Issue 12: the sun is spread as gendaymtx's AddDirect does (4 nearest centres, w = 1 / (1.002 - cos))."""
    sky_only = skyscatter.skymatrix(epw_file, scheme="reinhart2", samples=1)
    with_sun = skyscatter.skymatrix(epw_file, scheme="reinhart2", samples=1, include_sun=True)
    g = patch_scheme("reinhart2")
    diff = with_sun.luminance - sky_only.luminance
    assert np.all(diff >= 0)
    sunny = with_sun.sun_illuminance_normal > 0
    assert sunny.sum() > 10
    np.testing.assert_allclose((diff * g.solid_angles).sum(axis=1)[sunny], with_sun.sun_illuminance_normal[sunny],
                               rtol=1e-12)
    assert np.all(np.count_nonzero(diff[sunny], axis=1) == 4)
    centres = g.centre_directions.reshape(-1, 3)
    for h in np.flatnonzero(sunny & (with_sun.sun_zenith < 1.4)):
        z = max(with_sun.sun_zenith[h], math.radians(3.0))
        el, az = math.pi / 2 - z, with_sun.sun_azimuth[h]
        sun = np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])
        dots = centres @ sun
        nearest = np.argsort(-dots)[:4]
        assert set(np.flatnonzero(diff[h])) == set(nearest)
        w = 1 / (1.002 - dots[nearest])
        share = diff[h, nearest] * g.solid_angles[nearest] / with_sun.sun_illuminance_normal[h]
        np.testing.assert_allclose(share, w / w.sum(), rtol=1e-12)
        assert int(g.patch_index(sun)) in set(nearest)  # the patch containing the sun gets a share


def test_save_npz_and_csv(epw_file, tmp_path):
    m = skyscatter.skymatrix(epw_file, scheme="tregenza")
    npz = m.save_npz(tmp_path / "m.npz")
    with np.load(npz) as data:
        assert data["luminance"].shape == (48, 145)
        np.testing.assert_allclose(data["luminance"], m.luminance, rtol=1e-6)
        assert str(data["scheme"]) == "tregenza" and data["patch_solid_angle"].sum() == pytest.approx(2 * math.pi)
        assert data["times"][0] == "2023-06-20T00:30:00+01:00"
    csv = m.save_csv(tmp_path / "m.csv")
    lines = csv.read_text().splitlines()
    assert len(lines) == 49 and lines[0].startswith("time,patch_0,patch_1")
    row = np.array(lines[13].split(",")[1:], dtype=float)
    np.testing.assert_allclose(row, m.luminance[12], rtol=1e-5)


def test_progress_bar(epw_file, capsys):
    from skyscatter.sky_matrix import skymatrix

    m = skymatrix(epw_file, scheme="tregenza", progress=True, chunk_hours=5)
    assert skyscatter.skymatrix(epw_file, scheme="tregenza").luminance == pytest.approx(m.luminance)
    assert "48/48" in capsys.readouterr().err


@pytest.mark.parametrize("kwargs", [{"scheme": "nope"}, {"samples": 0}, {"samples": 17}, {"chunk_hours": 0}])
def test_bad_options(epw_file, kwargs):
    with pytest.raises(InvalidParameterError):
        skyscatter.skymatrix(epw_file, **kwargs)


def subhourly_records(n):
    """The two days of day_records() with n records per hour (minutes 60/n .. 60), same irradiance each."""
    rows = []
    for line in day_records():
        f = line.split(",")
        for k in range(n):
            g = list(f)
            g[4] = str((k + 1) * 60 // n)
            rows.append(",".join(g))
    return rows


def test_subhourly_file_one_row_per_record_or_hourly(tmp_path, epw_file):
    """Issue 12, item 1: a declared 4-per-hour file is read with each record's own interval; hourly() averages."""
    header = HEADER[:7] + ["DATA PERIODS,1,4,Data,Sunday, 6/20,6/21"]
    path = _write(tmp_path, header + subhourly_records(4))
    epw = read_epw(path)
    assert len(epw) == 4 * 48 and epw.records_per_hour == 4
    t = epw.times()
    # the k-th record of the hour ending at 1:00 covers [0:15 k, 0:15 (k + 1)]; stamps at the middles
    assert [x.strftime("%H:%M:%S") for x in t[:5]] == ["00:07:30", "00:22:30", "00:37:30", "00:52:30", "01:07:30"]
    assert len(set(t)) == len(t)
    hourly = epw.hourly()
    ref = read_epw(epw_file)
    assert len(hourly) == 48 and list(hourly.times()) == list(ref.times())
    np.testing.assert_array_equal(hourly.direct_normal_irradiance, ref.direct_normal_irradiance)
    m = skyscatter.skymatrix(path, scheme="tregenza", samples=1)
    assert m.shape == (4 * 48, 145) and len(set(m.times)) == 4 * 48
    mh = skyscatter.skymatrix(path, scheme="tregenza", samples=1, timestep="hourly")
    mr = skyscatter.skymatrix(epw_file, scheme="tregenza", samples=1)
    np.testing.assert_allclose(mh.luminance, mr.luminance, rtol=1e-12)


@pytest.mark.filterwarnings("ignore::skyscatter.epw.EPWWarning")  # the zones are far from the file's longitude
@pytest.mark.parametrize("zone,suffix", [(5.75, "+05:45"), (-3.5, "-03:30"), (0.0, "+00:00")])
def test_time_stamps_without_pandas_equal_the_pandas_ones(tmp_path, zone, suffix):
    """Issue 12: EPWData.unix_times and SkyMatrix.iso_times (numpy) give the instants and text pandas gives,
    also for time zones with minutes and west of Greenwich; times() and SkyMatrix.times are those instants."""
    header = [HEADER[0].replace(",1.0,520.0", f",{zone},520.0")] + HEADER[1:]
    assert header[0] != HEADER[0]
    path = tmp_path / "tz.epw"
    path.write_text("\n".join(header + day_records()) + "\n", encoding="utf-8")
    epw = read_epw(path)
    stamps = epw.times()
    np.testing.assert_array_equal(epw.unix_times(), stamps.asi8 / 1e9)
    np.testing.assert_array_equal(epw.unix_times(offset_hours=0.0), epw.times(offset_hours=0.0).asi8 / 1e9)
    m = skyscatter.skymatrix(path, scheme="tregenza", samples=1)
    assert list(m.iso_times()) == [t.isoformat() for t in stamps]
    assert m.iso_times()[0].endswith(suffix)
    assert list(m.times) == list(stamps)
    import pandas as pd

    dates = pd.to_datetime({"year": epw.year, "month": epw.month, "day": epw.day})
    np.testing.assert_array_equal(epw.day_of_year, dates.dt.day_of_year)
