"""Spectral pipeline: wavelength grids, CIE 1931 colorimetry, RGB conversion and the CIE daylight basis."""

from .colorimetry import (
    HDR_SCALE,
    LUMINOUS_EFFICACY,
    cie_cmfs,
    gamut_map_srgb,
    integration_weights,
    linear_srgb_to_xyz,
    spectrum_to_luminance,
    spectrum_to_xyz,
    xyY_to_xyz,
    xyz_to_chromaticity,
    xyz_to_linear_srgb,
)
from .daylight import daylight_basis, daylight_chromaticity, daylight_coefficients, daylight_spectrum
from .grid import DEFAULT_WAVELENGTHS, REFERENCE_WAVELENGTHS, as_wavelengths, wavelength_grid

__all__ = [
    "DEFAULT_WAVELENGTHS",
    "HDR_SCALE",
    "LUMINOUS_EFFICACY",
    "REFERENCE_WAVELENGTHS",
    "as_wavelengths",
    "cie_cmfs",
    "daylight_basis",
    "daylight_chromaticity",
    "daylight_coefficients",
    "daylight_spectrum",
    "gamut_map_srgb",
    "integration_weights",
    "linear_srgb_to_xyz",
    "spectrum_to_luminance",
    "spectrum_to_xyz",
    "wavelength_grid",
    "xyY_to_xyz",
    "xyz_to_chromaticity",
    "xyz_to_linear_srgb",
]
