"""Counter-based random numbers for the path tracer (numba, no state shared between tasks).

Every random number is a pure function of (seed, direction index, wavelength-group index, batch index, sample
index, draw number), so a Monte Carlo result depends only on the seed and the job, never on how the job was split
into tasks, in which order they ran, or on how many threads or workers ran them.

The key of a stream is built by chaining the SplitMix64 finaliser over the counters ([Steele2014]; finaliser
constants of Stafford's "Mix13"); the draws of one sample are successive outputs of SplitMix64 started at
``mix(key, sample index)``. Doubles take the top 53 bits: ``(x >> 11) * 2^-53`` in [0, 1).
"""

from __future__ import annotations

import numpy as np

from ..jit import helper, kernel

__all__ = ["mix64", "sample_state", "stream_key", "next_uniform", "uniforms"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_INV53 = 1.0 / 9007199254740992.0



@helper
def mix64(z: np.uint64) -> np.uint64:
    """SplitMix64 finaliser (a bijection of 64-bit integers)."""
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@helper
def stream_key(seed: int, direction: int, group: int, batch: int) -> np.uint64:
    """Key of the stream of one (direction, wavelength group, batch) for a seed."""
    k = mix64(np.uint64(seed) + _GOLDEN)
    k = mix64(k ^ (np.uint64(direction) + _GOLDEN))
    k = mix64(k ^ (np.uint64(group) * _M1 + _GOLDEN))
    return mix64(k ^ (np.uint64(batch) * _M2 + _GOLDEN))


@helper
def sample_state(key: np.uint64, sample: int) -> np.uint64:
    """Initial SplitMix64 state of sample number ``sample`` of a stream."""
    return mix64(key ^ (np.uint64(sample) * _GOLDEN + _M2))


@helper
def next_uniform(state: np.ndarray) -> float:
    """Advance ``state`` (a length-1 uint64 array) and return a double in [0, 1)."""
    state[0] = state[0] + _GOLDEN
    return float(mix64(state[0]) >> _S11) * _INV53


@kernel
def uniforms(seed: int, direction: int, group: int, batch: int, sample: int, n: int) -> np.ndarray:
    """The first ``n`` uniforms of one sample (for tests)."""
    st = np.empty(1, dtype=np.uint64)
    st[0] = sample_state(stream_key(seed, direction, group, batch), sample)
    out = np.empty(n)
    for i in range(n):
        out[i] = next_uniform(st)
    return out
