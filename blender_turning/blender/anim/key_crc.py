"""zlib's CRC-32 of buffers after a run of their bytes changed, without reading the rest.

CRC-32 is affine over GF(2): for messages of one length, ``crc(a ^ b) = crc(a) ^ L(b)`` with
``L`` linear (the register's advance from zero).  A change ``d`` of ``w`` bytes followed by
``tail`` unchanged bytes adds ``L(d + tail zero bytes) = Z^tail L(d)``, where ``Z`` advances the
register over one zero byte (the operator zlib's ``crc32_combine`` applies) and
``L(d) = crc(d) ^ crc(w zero bytes)``; the bytes before the change add nothing.  A Live Preview
drag step rewrites a few keys of long F-curves: their fingerprints (:mod:`.bake_layers`) follow
at the cost of the keys changed, not of the curves' length.
"""
from __future__ import annotations

import zlib
from functools import lru_cache

import numpy as np

#: zlib's CRC-32 polynomial, bit-reflected (the register shifts towards bit 0).
POLY = 0xEDB88320
_SHIFTS = np.arange(32, dtype=np.uint64)
_WEIGHTS = 2.0 ** np.arange(32)


def _bits(values) -> np.ndarray:
    """(..., 32) 0/1 as floats (exact; the products below run in BLAS): bit ``i`` of each
    32-bit value."""
    return ((np.asarray(values, np.uint64)[..., None] >> _SHIFTS) & 1).astype(float)


@lru_cache(maxsize=None)
def _zeros_pow2(k: int) -> np.ndarray:
    """(32, 32) 0/1: the register's advance over ``2**k`` zero bytes (``new = M @ old``)."""
    if k > 0:
        m = _zeros_pow2(k - 1)
        return m @ m % 2
    bit = np.zeros((32, 32))                     # one zero bit: r -> (r >> 1) ^ (r & 1) POLY
    bit[:, 0] = _bits(POLY)
    bit[np.arange(31), np.arange(1, 32)] = 1.0
    m = bit
    for _ in range(3):                           # 2, 4, 8 bits: a byte
        m = m @ m % 2
    return m


@lru_cache(maxsize=64)
def _zeros(count: int) -> np.ndarray:
    """(4, 256) uint64: the register's advance over ``count`` zero bytes, as tables of its
    value's four bytes (the advance of ``v`` is the xor of ``table[k][byte k of v]``)."""
    m = np.eye(32)
    for k in range(count.bit_length()):
        if count >> k & 1:
            m = m @ _zeros_pow2(k) % 2
    byte = np.arange(256, dtype=np.uint64)
    values = np.concatenate([byte << np.uint64(8 * k) for k in range(4)])
    return ((_bits(values) @ m.T % 2) @ _WEIGHTS).astype(np.uint64).reshape(4, 256)


def crc_after_change(crcs, old, new, tail: int) -> np.ndarray:
    """(m,) the CRC-32 (as ``zlib.crc32``) of each of ``m`` buffers whose CRCs were ``crcs``
    (m,) after the run of bytes ``old`` (m, ...) became ``new`` (the same shape and dtype, one
    row a buffer), with ``tail`` unchanged bytes after the run in every buffer."""
    d = np.bitwise_xor(np.ascontiguousarray(old).view(np.uint8),
                       np.ascontiguousarray(new).view(np.uint8)).reshape(len(crcs), -1)
    w, raw = d.shape[1], d.tobytes()
    zero = zlib.crc32(bytes(w))
    lin = np.array([zlib.crc32(raw[i:i + w]) ^ zero for i in range(0, len(raw), w)], np.uint64)
    table = _zeros(tail)
    out = np.asarray(crcs, np.uint64).copy()
    for k in range(4):
        out ^= table[k][(lin >> np.uint64(8 * k)) & np.uint64(255)]
    return out
