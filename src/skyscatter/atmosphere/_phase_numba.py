"""numba-compiled scalar versions of the phase functions of :mod:`.phase` (the same formula functions).

Imported on first access of ``skyscatter.atmosphere.phase.<name>_scalar`` so that importing the atmosphere
package does not import numba.
"""

from __future__ import annotations

import numba

from . import phase

_jit = numba.njit(cache=True, nogil=True, fastmath=False)

#: ``rayleigh_phase_scalar(mu)`` [sr^-1], Bruneton & Neyret (2008) Eq. 2.
rayleigh_phase_scalar = _jit(phase._rayleigh_formula)
#: ``henyey_greenstein_scalar(mu, g)`` [sr^-1].
henyey_greenstein_scalar = _jit(phase._henyey_greenstein_formula)
#: ``cornette_shanks_scalar(mu, g)`` [sr^-1], Bruneton & Neyret (2008) Eq. 4.
cornette_shanks_scalar = _jit(phase._cornette_shanks_formula)

_HENYEY_GREENSTEIN = phase.AEROSOL_PHASE_FUNCTIONS.index("henyey-greenstein")


@_jit
def aerosol_phase_scalar(mu, g, kind):
    """Aerosol phase function [sr^-1] of integer ``kind`` (:func:`.phase.aerosol_phase_kind`) at ``mu``."""
    if kind == _HENYEY_GREENSTEIN:
        return henyey_greenstein_scalar(mu, g)
    return cornette_shanks_scalar(mu, g)
