"""The light shafts' nodes (:func:`skyscatter.sky.broken_cloud_kernels.shaft_loss`: every wavelength of the air's
integrand only at some steps, linear in between, the shadow's spectral factor by its Taylor moments) against a
brute-force march written here in numpy: the same steps and the same lookups of the field's optical depth to the sun
(the shadow volume, the ground map), but every wavelength at every step, the shadow's factor ``1 - exp(-tau k)``
exactly and the air's transmittance stepped exactly (``int_step T dt = T_a (1 - exp(-beta dt)) / beta``), as the
kernel did before the nodes (until 2026-12-02)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.conventions import direction_from_angles
from skyscatter.sky import broken_cloud
from skyscatter.sky.broken_cloud import BrokenCloudSky

DROPS = CloudLayer(0.0, 1.0, 1.0, effective_radius=10e-6)


def _dirs(elevations_deg, azimuths_deg):
    return np.array([direction_from_angles(math.radians(90.0 - e), math.radians(a))
                     for e in elevations_deg for a in azimuths_deg])


def _tau_to_sun(sky, p):
    """The field's optical depth to the sun at the points ``p`` (n, 3) by the shafts' rules (docstring of
    :func:`~skyscatter.sky.broken_cloud_kernels.shaft_loss`): below the base the ground map at the foot of the sun
    ray, bilinear between column centres (periodic: wrapped; open: 0 outside), in the layer the voxel's value."""
    f = sky.field
    v = sky._volumes
    tg, ts = v["tau_ground"], v["tau_sun"]
    nx, ny, nz = ts.shape
    dx, dy, dz = f.voxel_size
    bottom = sky.clear.precomputed.parameters.bottom_radius
    sun = sky._sun_planet
    r = np.linalg.norm(p, axis=1)
    h = r - bottom
    mu_s = p @ sun / r
    lift = h / np.maximum(mu_s, 1e-3)
    fx = (p[:, 0] - lift * sun[0] - f.origin[0]) / dx - 0.5
    fy = (p[:, 1] - lift * sun[1] - f.origin[1]) / dy - 0.5
    i0 = np.floor(fx).astype(int)
    j0 = np.floor(fy).astype(int)
    ax, ay = fx - i0, fy - j0
    below = np.zeros(p.shape[0])
    for a in (0, 1):
        for b in (0, 1):
            ii, jj = i0 + a, j0 + b
            if f.periodic:
                ok = np.ones(ii.shape, dtype=bool)
                ii, jj = ii % nx, jj % ny
            else:
                ok = (ii >= 0) & (ii < nx) & (jj >= 0) & (jj < ny)
                ii, jj = np.clip(ii, 0, nx - 1), np.clip(jj, 0, ny - 1)
            w = (ax if a else 1 - ax) * (ay if b else 1 - ay)
            below += np.where(ok, w * tg[ii, jj], 0.0)
    gx = (p[:, 0] - f.origin[0]) / dx
    gy = (p[:, 1] - f.origin[1]) / dy
    if f.periodic:
        gx, gy = np.mod(gx, nx), np.mod(gy, ny)
    inside = (gx >= 0) & (gx < nx) & (gy >= 0) & (gy < ny)
    iz = np.clip(((r - bottom - f.base) / dz).astype(int), 0, nz - 1)
    layer = np.where(inside, ts[np.clip(gx.astype(int), 0, nx - 1), np.clip(gy.astype(int), 0, ny - 1), iz], 0.0)
    return np.where(r < bottom + f.base, below, layer), inside


def _brute_force(sky, eye, d, t0, length, t_start):
    """The loss and the gain (n_wl,) along ``eye + t d``, ``t0 <= t <= t0 + length``: midpoint steps of
    :data:`~skyscatter.sky.broken_cloud.SHAFT_STEP` growing as :data:`~skyscatter.sky.broken_cloud.SHAFT_GROWTH` x
    the distance; per step and wavelength the air's coefficients linear in altitude between the nodes of
    ``_shaft_air`` and ``E_0 T_air`` bilinear in altitude and sun cosine, ``t_start`` (n_wl,) the transmittance from
    the eye to ``t0``."""
    t_edges = [t0]
    while t_edges[-1] < t0 + length:
        t = t_edges[-1]
        t_edges.append(t + min(max(broken_cloud.SHAFT_STEP, broken_cloud.SHAFT_GROWTH * t), t0 + length - t))
    t_edges = np.array(t_edges)
    dt = np.diff(t_edges)
    tm = t_edges[:-1] + 0.5 * dt
    p = eye + tm[:, None] * d
    tab = sky.clear.precomputed
    air = tab.parameters
    bottom = air.bottom_radius
    r = np.linalg.norm(p, axis=1)
    h = r - bottom
    sun = sky._sun_planet
    mu_s = p @ sun / r
    tau, over = _tau_to_sun(sky, p)
    if sky.field.periodic:
        over[:] = True
    sa = sky._shaft_air
    nodes = np.arange(sa["beta_e"].shape[0]) * sa["h_step"]
    wl = tab.wavelengths

    def lin(table):  # linear in altitude between the nodes, clamped, (n_steps, n_wl)
        return np.stack([np.interp(h, nodes, table[:, w]) for w in range(wl.size)], axis=1)

    beta_r, beta_m, beta_e = lin(sa["beta_r"]), lin(sa["beta_m"]), lin(sa["beta_e"])
    mu = broken_cloud._MU_NODES
    v = np.clip((mu_s - mu[0]) / (mu[1] - mu[0]), 0.0, mu.size - 1.0)
    i_m = np.minimum(v.astype(int), mu.size - 2)
    a_m = (v - i_m)[:, None]
    e0 = np.empty((h.size, wl.size))
    for w in range(wl.size):
        lo = np.array([np.interp(h[i], nodes, sa["src"][:, i_m[i], w]) for i in range(h.size)])
        hi = np.array([np.interp(h[i], nodes, sa["src"][:, i_m[i] + 1, w]) for i in range(h.size)])
        e0[:, w] = lo * (1 - a_m[:, 0]) + hi * a_m[:, 0]
    nu = float(np.clip(d @ sun, -1.0, 1.0))
    p_r = float(air.rayleigh_phase(nu))
    p_m = air.aerosol_phase(np.array([nu]), wavelengths=wl)[0]
    k = sky._light["k"]
    shadow = 1.0 - np.exp(-np.multiply.outer(tau, k))
    ext = np.exp(-beta_e * dt[:, None])
    t_view = t_start * np.concatenate([np.ones((1, wl.size)), np.cumprod(ext, axis=0)[:-1]])
    seen = t_view * (1.0 - ext) / beta_e
    loss = np.sum(seen * (beta_r * p_r + beta_m * p_m) * e0 * shadow, axis=0)
    gain = np.sum(seen * (beta_r + beta_m) * over[:, None], axis=0) * sky._ground_up["air_light"]
    return loss, gain


def _segments(sky, eye, d):
    """Start and length of each ray's part below the field's top (no cloud, no ground limit), as :meth:`_shafts`."""
    bottom = sky.clear.precomputed.parameters.bottom_radius
    r_top = bottom + sky.field.top
    b = d @ eye
    c = float(eye @ eye)
    s = np.sqrt(np.maximum(b * b - (c - r_top**2), 0.0))
    t0 = np.where(c < r_top**2, 0.0, np.maximum(-b - s, 0.0))
    g = b * b - (c - bottom**2)
    t_planet = np.where((g >= 0) & (b < 0), np.maximum(-b - np.sqrt(np.maximum(g, 0.0)), 0.0), np.inf)
    return t0, np.minimum(-b + s, t_planet) - t0


CASES = {
    # sun 35 deg high (the benchmark's), from the ground: low, middle and steep rays towards and away from the sun
    "ground, sun 35 deg": (dict(cloud_cover=0.4, cloud_seed=1), 55.0, 0.0,
                           _dirs([1.0, 3.0, 8.0, 20.0, 45.0, 85.0], [135.0, 200.0, 315.0])),
    # a low sun: its light's transmittance changes fast with altitude (the nodes' criterion towards the sun)
    "ground, sun 6 deg": (dict(cloud_cover=0.6, cloud_seed=2, cloud_optical_depth=30.0), 84.0, 0.0,
                          _dirs([0.5, 2.0, 6.0, 15.0, 40.0], [100.0, 135.0, 250.0])),
    # from 6 km, above the field: rays entering its top sphere from outside, down to the ground
    "above, sun 35 deg": (dict(cloud_cover=0.5, cloud_seed=3), 55.0, 6000.0,
                          _dirs([-90.0, -60.0, -30.0, -10.0, -4.0], [0.0, 135.0, 270.0])),
    # an open field (no periodic copies) beside the observer: shadows and the clouds' light only over its box
    "open field, sun 20 deg": (dict(clouds=CloudField(np.random.default_rng(5).uniform(0.0, 0.02, (12, 12, 6)),
                                                      6000.0, 800.0, 2000.0, DROPS, origin=(-1000.0, 2000.0),
                                                      periodic=False)), 70.0, 0.0,
                               _dirs([1.0, 4.0, 10.0, 30.0, 70.0], [0.0, 20.0, 60.0, 135.0])),
}


@pytest.mark.parametrize("case", list(CASES))
def test_shaft_nodes_match_a_brute_force_march(case, monkeypatch):
    """Loss and gain of each ray within 0.3 % of the brute-force march's at every table wavelength (relative to
    the ray's own largest value over wavelength; measured: see docs/clouds.md); rays the brute force finds no
    shadow on lose nothing."""
    monkeypatch.setattr(broken_cloud, "_SHAFTS", True)
    kwargs, sun_zenith, altitude, d = CASES[case]
    sky = BrokenCloudSky(math.radians(sun_zenith), math.radians(135.0), altitude=altitude, **kwargs)
    assert sky._shaft_air["group"][0] > 1  # the nodes are in use (the air's coefficients are separable)
    eye = sky.clear.position
    loss, gain = sky._shafts(d, cloud_light=True)
    t0, length = _segments(sky, eye, d)
    tab = sky.clear.precomputed
    checked = 0
    worst = 0.0
    for i in range(d.shape[0]):
        if not length[i] > 0:
            assert not np.any(loss[i]) and not np.any(gain[i])
            continue
        t_start = (np.ones(tab.wavelengths.size) if t0[i] == 0.0 else
                   tab.aerial_perspective(eye, eye + t0[i] * d[i], sky._sun_planet)[0])
        ref_loss, ref_gain = _brute_force(sky, eye, d[i], t0[i], length[i], np.asarray(t_start).reshape(-1))
        if ref_loss.max() > 0:
            worst = max(worst, float(np.max(np.abs(loss[i] - ref_loss)) / ref_loss.max()))
            checked += 1
        else:
            assert not np.any(loss[i])
        if ref_gain.max() > 0:
            worst = max(worst, float(np.max(np.abs(gain[i] - ref_gain)) / ref_gain.max()))
    print(f"{case}: {checked} rays in shadow, largest deviation {worst:.2e}")
    assert checked >= 5
    assert worst < 3e-3
