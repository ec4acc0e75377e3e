"""Real-time rendering of the precomputed atmosphere: engine-ready textures, a GLSL library and a browser viewer.

* :mod:`.export` - the spectral tables folded into colour and packed as RGBA float32 / half / EXR textures, with a
  versioned JSON manifest that gives every mapping as code ([Bruneton2017]'s way of folding spectra).
* :mod:`.loader` - reading them back with the checks the viewer makes.
* ``glsl/atmosphere.glsl`` - GLSL ES 3.00 functions: transmittance, sky radiance, sun and sky irradiance, aerial
  perspective ([Bruneton2008]).
* :mod:`.server` and ``viewer/`` - the WebGL2 page of ``skyscatter view``, served from the package on 127.0.0.1.

Reference: [Bruneton2008], [Bruneton2017].
"""

from .export import MANIFEST_NAME, MANIFEST_VERSION, export_realtime
from .loader import RealtimeLuts, load_realtime, read_manifest

__all__ = ["MANIFEST_NAME", "MANIFEST_VERSION", "RealtimeLuts", "export_realtime", "load_realtime", "read_manifest"]
