"""Aerial perspective: how the air between a viewer and an object changes the object's radiance.

``L = L_0 tau + L_in`` (Preetham, Shirley & Smits 1999, Sec. 4). Models:

* :class:`PreethamAerialPerspective` -- the paper's two-species exponential atmosphere with in-scattering
  from the sun and sky (Eq. 7-11, A.4), analytic or numeric;
* :class:`ConstantDensityAerialPerspective` -- constant density along the ray, sunlight only (Preetham's
  course notes);
* :class:`WardLarsonAerialPerspective` -- the direction-independent "ambient" model the paper compares
  against in Figure 8.

* :class:`skyscatter.aerial.bruneton.BrunetonAerialPerspective` -- from the precomputed tables of Bruneton &
  Neyret (2008), with light shafts from a :class:`ShadowCaster` (imported from its module, which loads the
  tables' machinery).

All derive from :class:`AerialPerspective` (:mod:`skyscatter.aerial.base`: rays with origins), so
:class:`skyscatter.render.Scene` accepts any of them.
"""

from .base import AerialPerspective, ShadowCaster, as_aerial_perspective
from .constant_density import ConstantDensityAerialPerspective
from .integrals import ALPHA_HAZE, ALPHA_MOLECULES, effective_length, extinction, in_scattering_integrals
from .preetham import PreethamAerialPerspective
from .scattering import ScatteringTable, hemisphere_quadrature
from .ward_larson import ConstantColourSky, WardLarsonAerialPerspective

__all__ = [
    "ALPHA_HAZE",
    "ALPHA_MOLECULES",
    "AerialPerspective",
    "ConstantColourSky",
    "ConstantDensityAerialPerspective",
    "PreethamAerialPerspective",
    "ScatteringTable",
    "ShadowCaster",
    "WardLarsonAerialPerspective",
    "as_aerial_perspective",
    "effective_length",
    "extinction",
    "hemisphere_quadrature",
    "in_scattering_integrals",
]
