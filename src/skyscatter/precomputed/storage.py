"""Storing the tables: their identity (the cache key), the half-precision scattering tables, the ``.npz`` file
format, writing and verified, memory-mapped reading.

A table file is an ``.npz`` archive (uncompressed, readable by :func:`numpy.load`) with ``metadata``, a JSON text
(format name and :data:`FORMAT_VERSION`, library version, the key of :func:`cache_key`, the atmosphere
(:meth:`.AtmosphereParameters.to_dict`), orders, wavelengths [nm], sizes, a SHA-256 checksum per stored array and
the timings of the computation), and the arrays of :data:`STORED_NAMES`:

* ``transmittance`` and ``irradiance`` as float32, wavelength last (as :mod:`.tables` describes them);
* each 4D scattering table as :class:`HalfTable` stores it: ``<name>`` float16, wavelength first
  (n_wavelengths, n_r, n_mu, n_mu_s, n_nu), and ``<name>_scale`` float32 (n_wavelengths, n_r, n_mu_s), a power of
  two per wavelength, radius and sun zenith;
* with a tabulated aerosol phase (a Mie aerosol), the lookups' phase table (:data:`PHASE_NAMES`, float64).

Half precision halves the file and what a process maps (193 to 97 MiB for the default tables). Its rounding is
at most 2^-11 = 0.049 % of a value: each (wavelength, r, mu_s) slice is scaled by a power of two (exact) so that
its largest value lies in (2^12, 2^13], which keeps values down to 2^-26 of that largest one in float16's normal
range, where the relative rounding is that bound (the smaller ones are below 1e-8 of the slice's largest
value). Measured on the default tables in ``docs/bruneton.md``. The transmittance stays float32: the
aerial perspective divides transmittances (:func:`.sampling.transmittance_ratio`), which amplifies relative
errors near the horizon.

Every array is stored 64-byte aligned in the archive, so :func:`read_tables` maps the scattering tables
(:func:`numpy.memmap`) instead of reading them: a sky seen by one observer reads only the slices at its radius and
sun (:meth:`.evaluation.TableLookups.sky_xyz`), and the tables are decoded to float32 only when a lookup needs
all of them. The checksums are verified when the file is opened, over the stored bytes (the mapped pages of a
verified file are what the lookups read: the cache's files are replaced by renaming, never rewritten in place).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import struct
import zipfile
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..diskcache import array_checksum
from ..errors import FileFormatError, InvalidParameterError
from ..fileio import atomic_path
from .parameters import AtmosphereParameters
from .sizes import TableSizes

if TYPE_CHECKING:
    from .tables import PrecomputedAtmosphere

__all__ = ["FILE_FORMAT", "FORMAT_VERSION", "HALF_TABLES", "PHASE_NAMES", "STORED_NAMES", "TABLE_NAMES", "HalfTable",
           "cache_key", "checksum", "read_tables", "write_tables"]

#: Version of the table layout and algorithm; part of the cache key and checked by :func:`read_tables`.
#: 6: half-precision, wavelength-first scattering tables with power-of-two scales; 64-byte aligned arrays.
#: 7: the same layout; the scattering density on a double-Gauss zenith grid (low sun; docs/accuracy.md), so
#: tables of format 6 hold other values.
#: 8: the same layout; the ray integrals' view transmittance integrated along each ray (grazing rays near the
#: ground; docs/accuracy.md, "Low sun"), so tables of format 7 hold other values.
#: 9: the same layout; the first-order diffuse irradiance of a tabulated aerosol phase split by delta-M (its
#: forward peak exact; :func:`.kernels.indirect_irradiance_kernel`), so a Mie air's irradiance table changed.
#: 10: the same layout; the analytic aerosol phases' (Cornette-Shanks, Henyey-Greenstein) first-order diffuse
#: irradiance split by delta-M as well, so the default air's irradiance table changed (scattering tables did not).
#: 11: the same layout; a tabulated aerosol phase's orders computed in the delta-M scaled medium, its single
#: tables (two or more orders) with the scaled transmittances (the TMS correction; :mod:`.tables`), so a Mie air's
#: scattering and irradiance tables changed (the analytic phases' did not).
#: 12: the same layout; the scattering density interpolated log-linearly along the sun zenith and the view-sun
#: azimuth in the multiple-scattering ray integrals (:func:`.geometry.log_lerp_weight`; twilight: the Earth's
#: shadow), each wavelength's weight its own; the geometric tail of the orders with its ratio per sun zenith texel
#: (:func:`.compute.add_geometric_tail`), so the multiple-scattering tables of format 11 hold other values.
#: 13: the same layout; the second order's scattering density reads the single-scattering tables along the view-sun
#: azimuth with weights that follow the Earth's shadow (:func:`.sampling.shadow_nu_weights`; the same as before
#: wherever the sun is up at the texel), so the multiple-scattering tables of sun zeniths below the horizon changed.
#: 14: the same layout; the irradiance table read log-linearly along the sun zenith in its cells that start below the
#: horizon (:func:`.sampling.irradiance_read`: the ground term of the orders' scattering density) and the irradiance
#: integral of a sun below the horizon reading the scattering tables log-linearly along the sun zenith
#: (:func:`.sampling.scattering_lookup_log_mu_s`), so the irradiance and multiple-scattering tables of sun zeniths
#: below the horizon changed.
#: 15: the same layout; the scattering tables read, for rays that miss the ground, with a radius weight linear in the
#: altitude in the cells of rows that start above the ground and below 200 m (:func:`.geometry.scattering_r_index`;
#: before: linear in rho), in the orders' ray integrals and scattering density as in the rendering lookups, so the
#: multiple-scattering tables of format 14 hold other values.
#: 16: the same layout; in the cell of rows touching the ground (below the first row above it, 62.7 m of the default
#: 32 rows) the scattering tables are read, for rays that miss the ground, with a radius weight linear in the altitude
#: and each row at its own ``mu`` coordinate (:func:`.geometry.scattering_r_mu_rows`; before: linear in rho, one
#: shared coordinate), in the orders' ray integrals and scattering density as in the rendering lookups, so the
#: multiple-scattering tables of format 15 hold other values.
#: 17: the same layout; the irradiance table read quadratically in the logarithm over its three nearest sun-zenith
#: texels in the cells that start below the horizon (:func:`.geometry.log_quadratic_weight`; before: log-linear over
#: two) in the ground term of the orders' scattering density as in the rendering lookups, so the multiple-scattering
#: tables (and the irradiance tables of the orders after the second) of format 16 hold other values.
#: 18: the same layout; the rule of format 16 (rows apart, altitude weight) only where the cell touching the ground
#: ends below 300 m (:data:`.geometry.ALTITUDE_LINEAR_CELL_TOP`: 32 and 16 rows; tables of 8 rows keep the ``rho``
#: weight and a shared coordinate again), so tables with few rows of format 17 hold other values.
#: 19: the same layout; the multiple-scattering table (and the orders' scattering densities) hold their values
#: divided by the lobe :func:`.sampling.multiple_lobe` at each texel's view-sun cosine, so that every read between
#: the azimuth texels follows the aerosol's forward lobe; the lookups multiply by it at the read's own ``nu``.
#: 20: the same layout; the scattering density's sphere integral reads the previous order through four azimuth
#: texels (:func:`.sampling.scattering_lookup`, the rendering lookups' read of the multiple scattering), not linearly.
#: 21: the same layout; the second order's scattering density reads the single scattering from the Earth's shadow
#: with shadow factors up to :data:`.sampling.SHADOW_RATIO_MAX` (the rendering lookups' cap; before: 1), so the
#: multiple-scattering and irradiance tables of sun zeniths below the horizon changed.
#: 22: the same layout; the orders' ray integral reads the scattering density linearly along the azimuth, and along
#: the sun zenith log-linearly only where the cell's lower texel has the sun below +6 deg
#: (:data:`.kernels.LOG_SUN_ZENITH_BELOW`): the multiple-scattering tables changed, the sky by at most 0.21 %.
FORMAT_VERSION = 22
#: The ``format`` entry of a table file's metadata.
FILE_FORMAT = "skyscatter-bruneton-tables"
#: The tables of a precomputed atmosphere (their content: :mod:`.tables`).
TABLE_NAMES = ("transmittance", "irradiance", "single_rayleigh", "single_mie", "multiple")
#: The 4D tables stored in half precision (:class:`HalfTable`).
HALF_TABLES = ("single_rayleigh", "single_mie", "multiple")
#: The arrays of a table file, in file order.
STORED_NAMES = ("transmittance", "irradiance", *(f"{n}{s}" for n in HALF_TABLES for s in ("", "_scale")))
#: Arrays stored only with a tabulated aerosol phase (a Mie aerosol): the lookups' phase table at the tables'
#: wavelengths (:attr:`.evaluation.TableLookups._aerosol_phase`), so that a process that loads the tables does not
#: import the Mie library and recompute it (4-8 s of CPU, most of it miepython's import). Files without them
#: (written before) still load: the lookups then compute the table as before.
PHASE_NAMES = ("aerosol_phase_mu", "aerosol_phase_values")

#: Largest value of a slice after scaling: 2^13 (module docstring), so that rounding to float16 never moves it
#: past a power of two and encoding decoded values again gives the same scales and values.
_SCALED_MAX_EXPONENT = 13
#: Smallest exponent of a slice's scale: float32's smallest normal number, 2^-126.
_MIN_SCALE_EXPONENT = -126
#: Radius layers a :class:`HalfTable` keeps decoded (:meth:`HalfTable.radius_layer`).
_LAYERS_KEPT = 4
#: Bytes per block when streaming stored arrays (writing, checksums).
_BLOCK = 1 << 23
#: Alignment [bytes] of every array's data in a table file.
_ALIGN = 64
#: Header ID of the zip extra field that pads a member's data to the alignment (the value Android's zipalign uses;
#: zip readers skip extra fields they do not know).
_PAD_FIELD = 0xD935


class HalfTable:
    """A 4D scattering table in half precision: float16 values times a power of two per (wavelength, r, mu_s).

    ``values`` (n_wavelengths, n_r, n_mu, n_mu_s, n_nu) float16 and ``scale`` (n_wavelengths, n_r, n_mu_s) float32:
    the table is ``values * scale[:, :, None, :, None]``, seen wavelength last like the float32 tables of
    :mod:`.tables`: ``shape`` is (n_r, n_mu, n_mu_s, n_nu, n_wavelengths), indexing (``table[i_r, :, i_s]``) decodes
    only the part asked for, and :meth:`decode` the whole table. ``values`` may be a memory map of a table file
    (:func:`read_tables`) or of the spill file of a computation (``source``: the open file and offset of its
    bytes, for streaming them without mapping).
    """

    dtype = np.dtype(np.float32)

    def __init__(self, values: NDArray[np.float16], scale: NDArray[np.float32],
                 source: tuple[IO[bytes], int] | None = None) -> None:
        if values.dtype != np.float16 or values.ndim != 5 or scale.shape != (*values.shape[:2], values.shape[3]):
            raise FileFormatError(f"half-precision table of shape {values.shape} ({values.dtype}) with scales of "
                                  f"shape {scale.shape}: expected float16 (n_wl, n_r, n_mu, n_mu_s, n_nu) and "
                                  "(n_wl, n_r, n_mu_s)")
        self.values = values
        self.scale = np.ascontiguousarray(scale, dtype=np.float32)
        self.source = source
        n_l, n_r, n_mu, n_s, n_nu = values.shape
        self.shape = (n_r, n_mu, n_s, n_nu, n_l)
        self.ndim = 5
        self._moved = np.moveaxis(values, 0, -1)  # a view: wavelength last
        self._scale_b = np.broadcast_to(np.moveaxis(self.scale, 0, -1)[:, None, :, None, :], self.shape)

    def __getstate__(self) -> dict[str, Any]:
        # pickled (e.g. sent to another process) as plain arrays: a mapped file or spill file does not travel
        return {"values": np.array(self.values), "scale": self.scale}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["values"], state["scale"])  # type: ignore[misc]

    @classmethod
    def encode(cls, table: NDArray[np.floating]) -> HalfTable:
        """Round a float32 table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths), all values >= 0, to half precision."""
        values, scale = encode_half(table)
        return cls(values, scale)

    def __getitem__(self, key: Any) -> NDArray[np.float32]:
        if isinstance(key, tuple) and key and isinstance(key[0], (int, np.integer)):
            # one radius (the observer's slices): from that radius's decoded layer, kept for the next calls
            return self.radius_layer(int(key[0]))[key[1:]]
        return np.multiply(self._moved[key], self._scale_b[key], dtype=np.float32)

    def radius_layer(self, i_r: int) -> NDArray[np.float32]:
        """The table at radius index ``i_r``, decoded: (n_mu, n_mu_s, n_nu, n_wavelengths) float32. The last
        :data:`_LAYERS_KEPT` layers asked for are kept (2 MB each with the default sizes): the values of one radius
        lie in one block per wavelength of the wavelength-first layout, while a slice at one sun zenith is spread
        over the whole table (decoding the observer's slices directly took 5-30 ms per sky, a layer 1-2 ms once)."""
        i_r = range(self.shape[0])[i_r]  # negative indices, and IndexError outside
        layers = self.__dict__.setdefault("_layers", {})
        layer = layers.get(i_r)
        if layer is None:
            layer = np.multiply(np.moveaxis(self.values[:, i_r], 0, -1),
                                np.moveaxis(self.scale[:, i_r], 0, -1)[None, :, None, :], dtype=np.float32)
            while len(layers) >= _LAYERS_KEPT:
                layers.pop(next(iter(layers)))
            layers[i_r] = layer
        return layer

    def __array__(self, dtype: Any = None, copy: Any = None) -> NDArray[Any]:
        out = self.decode()
        return out if dtype is None else out.astype(dtype, copy=False)

    @property
    def nbytes(self) -> int:
        """Bytes stored (values and scales)."""
        return self.values.nbytes + self.scale.nbytes

    def decode(self) -> NDArray[np.float32]:
        """The whole table as float32 (n_r, n_mu, n_mu_s, n_nu, n_wavelengths), C-contiguous."""
        out = np.empty(self.shape, dtype=np.float32)
        for k in range(self.shape[0]):  # one radius at a time: the strided read of the transpose stays in cache
            np.multiply(self._moved[k], self._scale_b[k], out=out[k], dtype=np.float32)
        return out

    def blocks(self) -> Iterator[memoryview]:
        """The stored bytes of ``values``, in blocks, read from ``source`` when there is one (without mapping
        them: a computation streaming its spill file to a table file keeps them out of its resident memory)."""
        if self.source is None:
            flat = memoryview(np.ascontiguousarray(self.values)).cast("B")
            for i in range(0, flat.nbytes, _BLOCK):
                yield flat[i: i + _BLOCK]
            return
        fh, offset = self.source
        fd, end = fh.fileno(), offset + self.values.nbytes
        while offset < end:
            block = os.pread(fd, min(_BLOCK, end - offset), offset)
            if not block:
                raise OSError(f"spill file ended {end - offset} bytes early")
            offset += len(block)
            yield memoryview(block)


def encode_half(table: NDArray[np.floating]) -> tuple[NDArray[np.float16], NDArray[np.float32]]:
    """``(values, scale)`` of :class:`HalfTable` for a table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths) >= 0: per
    (wavelength, r, mu_s) the power of two that brings the largest value into (2^12, 2^13] (module docstring)."""
    t = np.asarray(table, dtype=np.float32)
    # Reductions and division in the table's own layout, one radius at a time: over the moved (wavelength-first)
    # view numpy strides across every value and the encoding took 0.6 s of CPU in a default precomputation; the
    # same arithmetic this way 0.15 s, with the same bits (the max over mu then over nu is the max over both).
    peak = t.max(axis=1).max(axis=2)  # (n_r, n_s, n_wl)
    if not np.all(np.isfinite(peak)) or np.any(t.min(axis=1).min(axis=2) < 0):
        raise InvalidParameterError("scattering tables must be finite and >= 0 to be stored in half precision")
    mantissa, exponent = np.frexp(peak)  # peak = m 2^e, m in [0.5, 1)
    ceil_log2 = np.where(mantissa > 0.5, exponent, exponent - 1)  # peak in (2^(k-1), 2^k]
    # the scale stays a normal float32 (>= 2^-126): a slice whose peak is below 2^-113 (a texel deep in the planet's
    # shadow under a thick haze) would otherwise get a scale of 0 and decode as inf * 0 = NaN; its values then keep
    # fewer bits, which at that level is nothing
    exponent = np.maximum(ceil_log2 - _SCALED_MAX_EXPONENT, _MIN_SCALE_EXPONENT)
    scale = np.where(peak > 0, np.ldexp(np.float32(1.0), exponent), 1.0).astype(np.float32)
    values = np.empty((t.shape[-1], *t.shape[:-1]), dtype=np.float16)
    # the values times the scales' reciprocals (powers of two: the same as the division), rounded to float16 by the
    # compiled loop, bit for bit numpy's cast (imported here: the kernels' module is not needed to read tables)
    from .kernels import half_bits_kernel

    half_bits_kernel(np.ascontiguousarray(t), (np.float32(1.0) / scale).astype(np.float32), values.view(np.uint16))
    scale = np.ascontiguousarray(np.moveaxis(scale, -1, 0))  # (n_wl, n_r, n_s)
    return values, scale


def checksum(arr: NDArray[Any] | HalfTable) -> str:
    """SHA-256 (hex) of an array's dtype, shape and bytes (of a :class:`HalfTable`: of its float16 values)."""
    h = hashlib.sha256()
    if isinstance(arr, HalfTable):
        h.update(f"{arr.values.dtype.str}{arr.values.shape}".encode())
        for block in arr.blocks():
            h.update(block)
        return h.hexdigest()
    return array_checksum(arr)


def cache_key(atmosphere: AtmosphereParameters, orders: int, wavelengths: NDArray[np.float64],
              sizes: TableSizes) -> str:
    """SHA-256 (hex) of the parameters, orders, wavelengths, sizes, library version and table format."""
    from .. import __version__  # the package's __init__ imports this package's modules: read at call time

    described = atmosphere.to_dict()
    if described.get("mie_phase_function") == "cornette-shanks":
        # the phase function the tables had before the field existed: keep the keys of existing caches
        del described["mie_phase_function"]
    blob = json.dumps(
        {
            "params": described,  # the key of every cache written so far: not renamed
            "orders": int(orders),
            "wavelengths": [float(w) for w in wavelengths],
            "sizes": dataclasses.asdict(sizes),
            "version": __version__,
            "format": FORMAT_VERSION,
        },
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _stored_arrays(stored: dict[str, Any]) -> dict[str, NDArray[Any] | HalfTable]:
    """The arrays of a table file (:data:`STORED_NAMES`) from the tables as stored (a :class:`HalfTable` for each
    4D table, standing for its values)."""
    out: dict[str, NDArray[Any] | HalfTable] = {"transmittance": stored["transmittance"],
                                                "irradiance": stored["irradiance"]}
    for name in HALF_TABLES:
        out[name] = stored[name]
        out[f"{name}_scale"] = stored[name].scale
    return out


def _checksums(arrays: dict[str, NDArray[Any] | HalfTable]) -> dict[str, str]:
    # hashlib releases the GIL on large buffers: the three large tables are hashed at once
    with ThreadPoolExecutor(max_workers=min(3, os.cpu_count() or 1)) as pool:
        sums = dict(zip(arrays, pool.map(checksum, arrays.values()), strict=True))
    return sums


def _metadata(atm: PrecomputedAtmosphere, checksums: dict[str, str]) -> dict[str, Any]:
    from .. import __version__  # as in cache_key

    return {
        "format": FILE_FORMAT,
        "format_version": FORMAT_VERSION,
        "library_version": __version__,
        "key": atm.cache_key,
        "parameters": atm.parameters.to_dict(),
        "orders": atm.orders,
        "wavelengths": [float(w) for w in atm.wavelengths],
        "sizes": dataclasses.asdict(atm.sizes),
        "checksums": checksums,
        "timings": atm.timings,
    }


def _write_member(zf: zipfile.ZipFile, fh: IO[bytes], name: str, arr: NDArray[Any] | HalfTable) -> None:
    """One ``.npy`` member, uncompressed, its data aligned to :data:`_ALIGN` bytes in the file (a padding extra
    field in its local header: the ``.npy`` header itself is a multiple of 64 bytes long)."""
    values = arr.values if isinstance(arr, HalfTable) else np.ascontiguousarray(arr)
    info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_STORED
    start = fh.tell() + 30 + len(info.filename.encode()) + 4  # local header, name, the padding field's header
    pad = -start % _ALIGN
    info.extra = struct.pack("<HH", _PAD_FIELD, pad) + bytes(pad)
    header = np.lib.format.header_data_from_array_1_0(values)
    with zf.open(info, "w") as out:
        np.lib.format.write_array_header_2_0(out, header)
        if isinstance(arr, HalfTable):
            for block in arr.blocks():
                out.write(block)
        else:
            out.write(memoryview(values).cast("B"))


def _phase_arrays(atm: PrecomputedAtmosphere) -> dict[str, NDArray[Any]]:
    """The :data:`PHASE_NAMES` arrays of ``atm`` (empty for an analytic aerosol phase)."""
    from .sampling import TABLE_PHASE

    kind, _, mu, values = atm._aerosol_phase
    if kind != TABLE_PHASE:
        return {}
    return {"aerosol_phase_mu": np.ascontiguousarray(mu, dtype=np.float64),
            "aerosol_phase_values": np.ascontiguousarray(values, dtype=np.float64)}


def write_tables(atm: PrecomputedAtmosphere, path: str | os.PathLike[str]) -> Path:
    """Write the tables and their description to an .npz file, atomically; returns the path."""
    target = Path(path)
    arrays = {**_stored_arrays(atm.stored), **_phase_arrays(atm)}
    meta = json.dumps(_metadata(atm, _checksums(arrays)), sort_keys=True)
    with atomic_path(target) as tmp, open(tmp, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_STORED) as zf:
        for name, arr in arrays.items():
            _write_member(zf, fh, name, arr)
        zf.writestr(zipfile.ZipInfo("metadata.npy", date_time=(1980, 1, 1, 0, 0, 0)), _npy_bytes(np.array(meta)))
    return target


def _npy_bytes(arr: NDArray[Any]) -> bytes:
    import io

    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, allow_pickle=False)
    return buf.getvalue()


def _member_arrays(p: Path) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """``(metadata, arrays)`` of a table file; the arrays memory-mapped (read-only) where they are stored
    uncompressed and aligned, read otherwise."""
    arrays: dict[str, NDArray[Any]] = {}
    with open(p, "rb") as fh, zipfile.ZipFile(fh) as zf:
        names = {info.filename[:-4]: info for info in zf.infolist() if info.filename.endswith(".npy")}
        with zf.open(names["metadata"]) as f:
            meta = json.loads(str(np.lib.format.read_array(f, allow_pickle=False)[()]))
        if not isinstance(meta, dict) or meta.get("format_version") != FORMAT_VERSION:
            return meta, arrays  # read_tables says what the file is
        for name in (*STORED_NAMES, *(n for n in PHASE_NAMES if n in names)):
            info = names[name]
            fh.seek(info.header_offset)
            local = fh.read(30)
            if len(local) != 30 or local[:4] != b"PK\x03\x04":
                raise ValueError("damaged member header")
            n_name, n_extra = struct.unpack("<HH", local[26:30])
            fh.seek(info.header_offset + 30 + n_name + n_extra)
            version = np.lib.format.read_magic(fh)
            shape, fortran, dtype = (np.lib.format.read_array_header_1_0(fh) if version == (1, 0)
                                     else np.lib.format.read_array_header_2_0(fh))
            offset = fh.tell()
            count = int(np.prod(shape)) * dtype.itemsize
            if info.compress_type != zipfile.ZIP_STORED or fortran or dtype.hasobject \
                    or offset % dtype.itemsize or offset + count > info.header_offset + 30 + n_name + n_extra \
                    + info.file_size:
                with zf.open(info) as f:  # not stored the way write_tables stores: read it
                    arrays[name] = np.lib.format.read_array(f, allow_pickle=False)
            elif count == 0:
                arrays[name] = np.zeros(shape, dtype=dtype)
            else:
                arrays[name] = np.memmap(p, dtype=dtype, mode="r", offset=offset, shape=shape)
    return meta, arrays


def read_tables(cls: type[PrecomputedAtmosphere], path: str | os.PathLike[str], *,
                expected_key: str | None = None) -> PrecomputedAtmosphere:
    """Tables written by :func:`write_tables`, as a ``cls``, verifying format, shapes and checksums; the
    scattering tables memory-mapped (module docstring).

    Raises
    ------
    FileFormatError
        If the file is not a skyscatter table file, is damaged, was written by another format version, or
        (with ``expected_key``) holds other parameters.
    """
    p = Path(path)
    try:
        meta, arrays = _member_arrays(p)
    except FileNotFoundError:
        raise
    except KeyError as exc:
        raise FileFormatError(f"{p}: not a skyscatter table file of this format (no table {exc})") from None
    except Exception:  # OSError, ValueError, zipfile.BadZipFile, JSON errors...
        # NumPy's messages (e.g. "allow_pickle=True") would mislead: say what the file should be instead.
        raise FileFormatError(
            f"{p}: not a readable skyscatter table file (damaged, or not an .npz written by "
            "'skyscatter precompute --out' or PrecomputedAtmosphere.save)"
        ) from None
    if not isinstance(meta, dict) or meta.get("format") != FILE_FORMAT:
        raise FileFormatError(f"{p}: not a skyscatter table file")
    if meta.get("format_version") != FORMAT_VERSION:
        raise FileFormatError(
            f"{p}: table format version {meta.get('format_version')} (this library reads {FORMAT_VERSION})"
        )
    try:
        tables: dict[str, NDArray[Any] | HalfTable] = {"transmittance": arrays["transmittance"],
                                                       "irradiance": arrays["irradiance"]}
        for name in HALF_TABLES:
            tables[name] = HalfTable(arrays[name], arrays[f"{name}_scale"])
    except FileFormatError as exc:
        raise FileFormatError(f"{p}: {exc}") from None
    phase = {name: np.array(arrays[name]) for name in PHASE_NAMES if name in arrays}
    if phase and len(phase) != len(PHASE_NAMES):
        raise FileFormatError(f"{p}: not a readable skyscatter table file (one of {', '.join(PHASE_NAMES)} missing)")
    expected = meta.get("checksums", {})
    for name, value in _checksums({**_stored_arrays(tables), **phase}).items():
        if value != expected.get(name):
            raise FileFormatError(f"{p}: checksum mismatch in table {name!r} (file damaged)")
    try:
        atmosphere = AtmosphereParameters.from_dict(meta["parameters"])
        sizes = TableSizes(**meta["sizes"])
        # a file's tables are the precomputation's of its parameters (its key is checked below)
        atm = cls(atmosphere, meta["wavelengths"], sizes, meta["orders"], tables, meta.get("timings"), computed=True)
    except (KeyError, TypeError, InvalidParameterError) as exc:
        raise FileFormatError(f"{p}: inconsistent table description ({exc})") from None
    if atm.cache_key != meta.get("key"):
        raise FileFormatError(f"{p}: the stored key does not match the stored parameters")
    if expected_key is not None and meta.get("key") != expected_key:
        raise FileFormatError(f"{p}: tables were computed for other parameters, sizes or library version")
    if phase:
        _set_phase(atm, phase, p)
    return atm


def _set_phase(atm: PrecomputedAtmosphere, phase: dict[str, NDArray[Any]], p: Path) -> None:
    """Give ``atm``'s lookups the stored aerosol phase table (:data:`PHASE_NAMES`) after checking that it fits."""
    from .sampling import TABLE_PHASE

    mu, values = phase["aerosol_phase_mu"], phase["aerosol_phase_values"]
    if (atm.parameters.aerosol_component.analytic_phase is not None or mu.ndim != 1 or mu.size < 3
            or mu[0] != -1.0 or mu[-1] != 1.0 or values.shape != (len(atm.wavelengths), mu.size)
            or not np.all(np.diff(mu) > 0) or not np.all(np.isfinite(values)) or np.any(values < 0)):
        raise FileFormatError(f"{p}: inconsistent stored aerosol phase table")
    atm._aerosol_phase_cache = (TABLE_PHASE, 0.0, mu, values)

