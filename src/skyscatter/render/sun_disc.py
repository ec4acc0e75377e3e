"""The solar disc in an image, energy-true at any resolution and projection.

An image pixel holds the mean radiance over its footprint, and a renderer reading an environment map (Blender's
Environment Texture, Mitsuba's ``envmap``) reconstructs the radiance between pixel centres by bilinear
interpolation. The disc is therefore deposited with the bilinear (tent) kernel of the pixel grid: the value of
pixel i is

    L_i = (1 / Omega_i) * integral over the disc of L_sun(w) K_i(w) dw,

with ``K_i`` the tent of pixel i in image coordinates (the kernels sum to 1 everywhere) and ``Omega_i`` the
pixel's solid angle (:func:`skyscatter.render.sky_image.pixel_solid_angles`). Then

* the image's flux ``sum_i L_i Omega_i`` equals the disc's normal irradiance exactly, at any width (a disc smaller
  than a pixel is splatted over the 2 x 2 pixels around it, a large one is drawn with antialiased edges); and
* the first moment is kept: ``sum_i L_i Omega_i f(w_i)`` is the disc integral of the bilinear interpolant of f,
  so the irradiance a renderer (or a midpoint quadrature over the map) finds on any plane is the sun's
  ``E_n cos(incidence)`` to second order in the pixel size.

A box filter (each pixel's covered fraction) keeps the flux too but moves the disc's centroid by up to a tenth of
a pixel; for a low sun that changes the horizontal illuminance by ``tan(zenith)`` times that angle (1 % at 2 deg
elevation and width 1024, measured in docs/conventions.md, "The solar disc in images"), which is why the tent
is used.

The integral is a quadrature over a sub-pixel grid covering the disc only (never the whole image): at least 8
sub-samples across the disc radius and 2 per pixel along each image axis, each sub-sample weighted by its solid
angle and by its covered fraction of the disc edge (linear in the distance to the limb). The quadrature is then
scaled to the disc's exact solid angle, so the flux is exact to rounding whenever the disc's box lies inside the
image. Limb darkening (Hosek & Wilkie 2013) enters as a radial
profile, linear between 33 nodes in relative radius, normalised so that the disc's flux is its disc-averaged
radiance times its solid angle.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..conventions import direction_from_angles
from ..sky.base import SolarDisc
from ..spectral import REFERENCE_WAVELENGTHS, spectrum_to_xyz

__all__ = ["DiscDeposit", "EquirectProjection", "FisheyeProjection", "PinholeProjection", "disc_deposit",
           "disc_profile_xyz", "disc_profile_spectral", "LIMB_NODES", "profile_nodes_for"]

#: Nodes (relative radii 0, 1/32, ..., 1) of a limb-darkened disc's radial profile (linear between them).
LIMB_NODES = 33
#: Sub-samples across the disc's radius (at least) and per pixel along each axis (at least); at most per pixel.
_PER_RADIUS, _PER_PIXEL, _MAX_PER_PIXEL = 8, 2, 64
#: Sub-samples evaluated per vectorised step (bounds the working memory to some tens of MB).
_CHUNK = 1 << 20


def _unit(zenith: NDArray[np.float64], azimuth: NDArray[np.float64]) -> NDArray[np.float64]:
    """ENU unit vectors (..., 3) from zenith and azimuth [rad] (``conventions.direction_from_angles`` without its
    input checks: the arguments here are computed, not given)."""
    st = np.sin(zenith)
    return np.stack([st * np.sin(azimuth), st * np.cos(azimuth), np.cos(zenith)], axis=-1)


class _Projection(abc.ABC):
    """A continuous map between image coordinates (x right, y down, in pixels; pixel (i, j) spans
    [j, j + 1) x [i, i + 1)) and unit ENU directions."""

    width: int
    height: int
    wraps = False  # columns wrap around (the full-sphere equirectangular map)

    @abc.abstractmethod
    def to_pixel(self, d: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """(x, y, valid) of directions (..., 3)."""

    @abc.abstractmethod
    def from_pixel(self, x: NDArray, y: NDArray) -> NDArray[np.float64]:
        """Unit directions (..., 3) at image coordinates (x, y)."""

    @abc.abstractmethod
    def solid_angle_density(self, x: NDArray, y: NDArray, d: NDArray[np.float64]) -> NDArray[np.float64]:
        """Solid angle per unit image area [sr px^-2] at (x, y) (direction ``d`` there)."""

    def in_view(self, d: NDArray[np.float64], x: NDArray, y: NDArray) -> NDArray[np.bool_]:
        """Whether the sub-sample at (x, y), direction ``d``, lies in the image's field of view."""
        return (x >= 0) & (x <= self.width) & (y >= 0) & (y <= self.height)

    def pixel_allowed(self, rows: NDArray, cols: NDArray) -> NDArray[np.bool_]:
        """Pixels (within the array) that may receive light: all, or those inside a fisheye's horizon circle."""
        return np.ones(np.shape(rows), dtype=bool)


class EquirectProjection(_Projection):
    """Full-sphere latitude-longitude map: ``theta = pi y / H``, ``phi = 2 pi (x / W - north_column)``."""

    wraps = True

    def __init__(self, width: int, height: int, north_column: float = 0.5) -> None:
        self.width, self.height, self.north_column = int(width), int(height), float(north_column)

    def to_pixel(self, d):
        theta = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
        phi = np.arctan2(d[..., 0], d[..., 1])
        x = np.mod(self.width * (phi / (2.0 * math.pi) + self.north_column), self.width)
        return x, self.height * theta / math.pi, np.ones(theta.shape, dtype=bool)

    def from_pixel(self, x, y):
        return _unit(math.pi * np.asarray(y) / self.height, 2.0 * math.pi * (np.asarray(x) / self.width
                                                                               - self.north_column))

    def solid_angle_density(self, x, y, d):
        return (2.0 * math.pi / self.width) * (math.pi / self.height) * np.sin(math.pi * np.asarray(y) / self.height)

    def in_view(self, d, x, y):
        return (y >= 0) & (y <= self.height)


class FisheyeProjection(_Projection):
    """Equidistant upper hemisphere, zenith at the centre, north up, east left (``fisheye_directions``)."""

    def __init__(self, size: int) -> None:
        self.width = self.height = int(size)

    def to_pixel(self, d):
        theta = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
        phi = np.arctan2(d[..., 0], d[..., 1])
        r = theta / (math.pi / 2.0)
        return (1.0 - r * np.sin(phi)) * self.width / 2.0, (1.0 - r * np.cos(phi)) * self.width / 2.0, r <= 2.0

    def from_pixel(self, x, y):
        px = 2.0 * np.asarray(x) / self.width - 1.0
        py = 2.0 * np.asarray(y) / self.width - 1.0
        return _unit(np.hypot(px, py) * (math.pi / 2.0), np.arctan2(-px, -py))

    def solid_angle_density(self, x, y, d):
        theta = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
        return (math.pi / self.width) ** 2 * np.sinc(theta / math.pi)

    def in_view(self, d, x, y):
        return d[..., 2] >= 0.0

    def pixel_allowed(self, rows, cols):
        c = 2.0 / self.width
        return np.hypot((cols + 0.5) * c - 1.0, (rows + 0.5) * c - 1.0) <= 1.0  # as fisheye_directions' mask


class PinholeProjection(_Projection):
    """Rectilinear camera (heading, pitch, horizontal fov [rad]) as ``pinhole_directions``."""

    def __init__(self, width: int, height: int, heading: float, pitch: float, fov: float) -> None:
        self.width, self.height = int(width), int(height)
        self.forward = direction_from_angles(math.pi / 2 - pitch, heading)
        self.right = np.array([math.cos(heading), -math.sin(heading), 0.0])
        self.up = np.cross(self.right, self.forward)
        self.half_w = math.tan(fov / 2.0)
        self.half_h = self.half_w * self.height / self.width

    def to_pixel(self, d):
        t = d @ self.forward
        valid = t > 1e-6
        safe = np.where(valid, t, 1.0)
        sx = (d @ self.right) / safe
        sy = (d @ self.up) / safe
        return (sx / self.half_w + 1.0) * self.width / 2.0, (1.0 - sy / self.half_h) * self.height / 2.0, valid

    def from_pixel(self, x, y):
        sx = (np.asarray(x) / self.width * 2.0 - 1.0) * self.half_w
        sy = (1.0 - np.asarray(y) / self.height * 2.0) * self.half_h
        d = self.forward + sx[..., None] * self.right + sy[..., None] * self.up
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def solid_angle_density(self, x, y, d):
        return (2.0 * self.half_w / self.width) ** 2 * np.clip(d @ self.forward, 0.0, None) ** 3


@dataclass(frozen=True)
class DiscDeposit:
    """The disc's share of each pixel it touches.

    Attributes
    ----------
    rows, cols : ndarray of int, shape (n,)
        The pixels.
    weights : ndarray, shape (n, n_nodes)
        ``L_i = weights[i] @ profile`` with ``profile[k]`` the disc's radiance at relative radius ``radii[k]``
        (any unit, any channels: a spectrum or XYZ; the profile is linear between nodes); see
        :func:`disc_profile_xyz`.
    radii : ndarray, shape (n_nodes,)
        Relative radii (0 centre, 1 limb) of the profile's nodes: 0 alone for a uniform disc.
    solid_angles : ndarray, shape (n_nodes,)
        The disc's solid angle [sr] carried by each node (the quadrature of its linear hat over the whole disc);
        they sum to the disc's ``2 pi (1 - cos r)``, so a profile with ``solid_angles @ profile = mean * Omega``
        gives the exact flux.
    complete : bool
        True when the whole disc lies in the image (the flux in the image is then exact); False when part of it
        is outside the field of view (a pinhole's frame, below a fisheye's horizon).
    """

    rows: NDArray[np.int64]
    cols: NDArray[np.int64]
    weights: NDArray[np.float64]
    radii: NDArray[np.float64]
    solid_angles: NDArray[np.float64]
    complete: bool

    def values(self, profile: NDArray[np.float64]) -> NDArray[np.float64]:
        """Pixel values (n, channels) for a radiance profile (n_nodes, channels)."""
        return self.weights @ np.asarray(profile, dtype=float).reshape(self.weights.shape[1], -1)


def _basis(s: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors orthogonal to ``s`` and to each other."""
    x, y, z = (float(v) for v in s)
    e1 = np.array([0.0, z, -y]) if abs(x) < 0.9 else np.array([-z, 0.0, x])  # s x (1, 0, 0), s x (0, 1, 0)
    e1 /= math.sqrt(float(e1 @ e1))
    e2 = np.array([y * e1[2] - z * e1[1], z * e1[0] - x * e1[2], x * e1[1] - y * e1[0]])  # s x e1
    return e1, e2


def _bounding_box(s, radius, proj: _Projection) -> tuple[float, float, float, float] | None:
    """(x0, x1, y0, y1) image box around the disc, or None when none of it projects into the image."""
    e1, e2 = _basis(s)
    t = np.linspace(0.0, 2.0 * math.pi, 97)[:-1]
    ring = (math.cos(radius) * s + math.sin(radius) * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2))
    pts = np.vstack([s[None, :], ring])
    x, y, valid = proj.to_pixel(pts)
    if not np.any(valid):
        return None
    x, y = x[valid], y[valid]
    w, h = proj.width, proj.height
    if proj.wraps:
        x = x[0] + np.mod(x - x[0] + w / 2.0, w) - w / 2.0  # unwrap around the centre's column
        pole_in = np.arccos(np.clip(abs(s[2]), 0.0, 1.0)) <= radius * 1.05
        if pole_in or x.max() - x.min() >= w / 2.0:
            x0, x1 = 0.0, float(w)
            y0, y1 = (0.0, float(y.max())) if s[2] > 0 else (float(y.min()), float(h))
        else:
            x0, x1, y0, y1 = float(x.min()), float(x.max()), float(y.min()), float(y.max())
        pad = 0.05 * max(y1 - y0, 1e-9)  # the ring's 96 points cut the extreme corners of the projected disc
        return x0 - (pad if x1 - x0 < w else 0.0), x1 + (pad if x1 - x0 < w else 0.0), max(0.0, y0 - pad), min(
            float(h), y1 + pad)
    x0, x1, y0, y1 = float(x.min()), float(x.max()), float(y.min()), float(y.max())
    pad = 0.05 * max(x1 - x0, y1 - y0, 1e-9)
    x0, x1, y0, y1 = max(x0 - pad, -1.0), min(x1 + pad, w + 1.0), max(y0 - pad, -1.0), min(y1 + pad, h + 1.0)
    if x0 >= x1 or y0 >= y1:
        return None
    return x0, x1, y0, y1


def disc_deposit(direction: NDArray[np.float64], angular_radius: float, proj: _Projection, *,
                 nodes: int = 1) -> DiscDeposit | None:
    """The pixels a disc of ``angular_radius`` [rad] around unit ``direction`` touches, and their weights.

    See the module docstring for the method. ``nodes`` > 1 samples a radial profile (limb darkening) at that
    many relative radii from 0 to 1, linear between them. Returns None when no part of the disc is in the image.
    """
    s = np.asarray(direction, dtype=float)
    s = s / np.linalg.norm(s)
    r = float(angular_radius)
    box = _bounding_box(s, r, proj)
    if box is None:
        return None
    x0, x1, y0, y1 = box
    w, h = proj.width, proj.height
    # Sub-sample spacing: at least 8 across the radius and 2 per pixel on each axis.
    nx = int(min(_MAX_PER_PIXEL, max(_PER_PIXEL, math.ceil(2 * _PER_RADIUS / max(x1 - x0, 1e-9)))))
    ny = int(min(_MAX_PER_PIXEL, max(_PER_PIXEL, math.ceil(2 * _PER_RADIUS / max(y1 - y0, 1e-9)))))
    kx0, kx1 = math.floor(x0 * nx), math.ceil(x1 * nx)
    ky0, ky1 = math.floor(y0 * ny), math.ceil(y1 * ny)
    xs = (np.arange(kx0, kx1) + 0.5) / nx
    if proj.wraps and x1 - x0 >= w:
        xs = (np.arange(0, w * nx) + 0.5) / nx
    ys_all = (np.arange(ky0, ky1) + 0.5) / ny
    area = 1.0 / (nx * ny)  # of a sub-sample [px^2]
    clipped = not proj.wraps and (x0 <= -1.0 or y0 <= -1.0 or x1 >= w + 1.0 or y1 >= h + 1.0)
    nodes = max(1, int(nodes))
    keys_parts, vals_parts = [], []
    total_all = np.zeros(nodes)  # quadrature of each profile node over every sub-sample (in view or not)
    complete = not clipped
    rows_per_chunk = max(1, _CHUNK // max(1, xs.size))
    for c0 in range(0, ys_all.size, rows_per_chunk):
        ys = ys_all[c0:c0 + rows_per_chunk]
        X, Y = np.meshgrid(xs, ys)
        X, Y = X.ravel(), Y.ravel()
        d = proj.from_pixel(np.mod(X, w) if proj.wraps else X, Y)
        cosang = d @ s
        near = cosang > math.cos(r * 1.5)
        if not np.any(near):
            continue
        X, Y, d, cosang = X[near], Y[near], d[near], cosang[near]
        diff = d - s
        rho = 2.0 * np.arcsin(np.minimum(0.5 * np.sqrt(np.einsum("ij,ij->i", diff, diff)), 1.0))  # exact near s
        dens = proj.solid_angle_density(X, Y, d)
        step = np.sqrt(dens * area)  # angular size of a sub-sample [rad]
        cover = np.clip((r - rho) / np.maximum(step, 1e-300) + 0.5, 0.0, 1.0)
        keep = cover > 0.0
        if not np.any(keep):
            continue
        X, Y, d, rho, dens, cover = X[keep], Y[keep], d[keep], rho[keep], dens[keep], cover[keep]
        weight = dens * area * cover  # solid angle of the disc in each sub-sample [sr]
        # the radial profile: linear between nodes at relative radii k / (nodes - 1)
        if nodes == 1:
            node = np.zeros((weight.size, 1), dtype=np.int64)
            node_w = weight[:, None]
        else:
            t = np.minimum(rho / r, 1.0) * (nodes - 1)
            k0 = np.minimum(np.floor(t).astype(np.int64), nodes - 2)
            ft = t - k0
            node = np.stack([k0, k0 + 1], axis=-1)
            node_w = weight[:, None] * np.stack([1.0 - ft, ft], axis=-1)
        total_all += np.bincount(node.ravel(), weights=node_w.ravel(), minlength=nodes)
        view = proj.in_view(d, X, Y)
        if not np.all(view):
            complete = False
            X, Y, node, node_w = X[view], Y[view], node[view], node_w[view]
        # bilinear (tent) split over the four pixel centres around each sub-sample
        xc, yc = X - 0.5, Y - 0.5
        j0, i0 = np.floor(xc).astype(np.int64), np.floor(yc).astype(np.int64)
        fx, fy = xc - j0, yc - i0
        nbr_rows = np.stack([i0, i0, i0 + 1, i0 + 1], axis=-1)
        nbr_cols = np.stack([j0, j0 + 1, j0, j0 + 1], axis=-1)
        nbr_w = np.stack([(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy], axis=-1)
        if proj.wraps:
            nbr_cols = np.mod(nbr_cols, w)
            nbr_rows = np.clip(nbr_rows, 0, h - 1)  # beyond the first/last row centre: the pole's own row
            ok = np.ones(nbr_rows.shape, dtype=bool)
        else:
            ok = (nbr_rows >= 0) & (nbr_rows < h) & (nbr_cols >= 0) & (nbr_cols < w)
            ok[ok] = proj.pixel_allowed(nbr_rows[ok], nbr_cols[ok])
        nbr_w = np.where(ok, nbr_w, 0.0)
        norm = nbr_w.sum(axis=-1)
        lost = norm <= 0.0
        if np.any(lost):
            complete = False
        nbr_w = nbr_w / np.where(lost, 1.0, norm)[:, None]
        pix = nbr_rows * w + nbr_cols  # (m, 4)
        keys = pix[:, :, None] * nodes + node[:, None, :]  # (m, 4, 2)
        vals = nbr_w[:, :, None] * node_w[:, None, :]
        sel = np.broadcast_to((ok & (nbr_w > 0.0))[:, :, None], keys.shape)
        keys_parts.append(keys[sel])
        vals_parts.append(vals[sel])
    if not keys_parts or total_all.sum() <= 0.0:
        return None
    keys = np.concatenate(keys_parts)
    vals = np.concatenate(vals_parts)
    if keys.size == 0:
        # every sub-sample outside the image's allowed pixels (a sun below the horizon of a fisheye: its box lies in
        # the image's corners); np.bincount of nothing is an integer array, which the scaling below cannot take
        return None
    # per pixel and node: the pixels touched, then their weights (one sort of the pixel numbers)
    pix_all, node_all = np.divmod(keys, nodes)
    upix, pinv = np.unique(pix_all, return_inverse=True)
    weights = np.bincount(pinv * nodes + node_all, weights=vals, minlength=upix.size * nodes).reshape(upix.size,
                                                                                                    nodes)
    # The quadrature scaled to the disc's exact solid angle (when it saw the whole disc): flux exact to rounding.
    omega_disc = 2.0 * math.pi * (1.0 - math.cos(r))
    scale = omega_disc / total_all.sum() if not clipped else 1.0
    weights *= scale
    rows, cols = np.divmod(upix, w)
    x = (cols + 0.5).astype(float)
    y = (rows + 0.5).astype(float)
    weights /= proj.solid_angle_density(x, y, proj.from_pixel(x, y))[:, None]
    radii = np.linspace(0.0, 1.0, nodes) if nodes > 1 else np.zeros(1)
    return DiscDeposit(rows.astype(np.int64), cols.astype(np.int64), weights, radii, total_all * scale, complete)


def disc_profile_spectral(sun: SolarDisc, deposit: DiscDeposit, wavelengths: NDArray[np.float64]
                          ) -> NDArray[np.float64]:
    """Spectral radiance [W m^-2 sr^-1 nm^-1] at each profile node of ``deposit``, shape (n_nodes, n_wavelengths).

    The disc-averaged radiance times the limb darkening at each node's radius, normalised so that the disc's
    spectral irradiance in the image is its disc average times its solid angle exactly.
    """
    mean = np.asarray(sun.spectral_radiance(wavelengths), dtype=float)
    n = deposit.radii.size
    if sun.limb_darkening is None or n == 1:
        return np.broadcast_to(mean, (n, mean.size)).copy()
    ld = np.asarray(sun.limb_darkening(deposit.radii, wavelengths), dtype=float)  # (n, n_wl)
    total = deposit.solid_angles @ ld
    omega = deposit.solid_angles.sum()
    with np.errstate(divide="ignore", invalid="ignore"):
        norm = np.where(total > 0, omega / total, 0.0)
    return mean[None, :] * ld * norm[None, :]


def disc_profile_xyz(sun: SolarDisc, deposit: DiscDeposit) -> NDArray[np.float64]:
    """CIE XYZ [cd m^-2] at each profile node of ``deposit`` (n_nodes, 3), carrying ``sun.xyz()`` times the disc's
    solid angle (for a uniform disc, the one node is ``sun.xyz()``)."""
    if sun.limb_darkening is None or deposit.radii.size == 1:
        xyz = np.asarray(sun.xyz(), dtype=float)
        return np.broadcast_to(xyz, (deposit.radii.size, 3)).copy()
    spectra = disc_profile_spectral(sun, deposit, REFERENCE_WAVELENGTHS)
    return spectrum_to_xyz(spectra, REFERENCE_WAVELENGTHS)


def profile_nodes_for(sun: SolarDisc) -> int:
    """Nodes of a disc's radial profile: 1 for a uniform disc, :data:`LIMB_NODES` with limb darkening."""
    return 1 if sun.limb_darkening is None else LIMB_NODES
