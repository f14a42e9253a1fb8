"""The CRC-32 of a buffer after a run of its bytes changed (blender/anim/key_crc.py), against
zlib's CRC of the whole changed buffer: the fingerprints of a Live Preview drag step's keys."""
import zlib

import numpy as np
import pytest

from blender_turning.blender.anim.key_crc import crc_after_change


@pytest.mark.parametrize("total, i0, n", [(1441, 720, 5), (1441, 0, 5), (1441, 1436, 5),
                                          (241, 118, 5), (10, 3, 1), (7, 0, 7),
                                          (60001, 30000, 5)])
def test_the_crc_after_a_change_is_zlibs_of_the_changed_buffer(total, i0, n):
    rng = np.random.default_rng(total + i0)
    keys = rng.normal(size=(6, 2 * total)).astype(np.float32)    # (frame, value) per key
    new = keys.copy()
    new[:, 2 * i0 + 1:2 * (i0 + n):2] = rng.normal(size=(6, n))
    new[0, 2 * i0 + 1] = keys[0, 2 * i0 + 1]                     # one key written unchanged
    new[1, 2 * i0 + 1:2 * (i0 + n):2] = keys[1, 2 * i0 + 1:2 * (i0 + n):2]    # none changed
    window = slice(2 * i0, 2 * (i0 + n))
    got = crc_after_change([zlib.crc32(k.tobytes()) for k in keys], keys[:, window],
                           new[:, window], 4 * 2 * (total - i0 - n))
    assert got.tolist() == [zlib.crc32(k.tobytes()) for k in new]


def test_a_change_of_one_byte_anywhere():
    """Every byte of a run, changed alone, at every distance from the end up to 3 bytes, and
    far from it (the register's advance over 2**k zero bytes, k up to 20)."""
    rng = np.random.default_rng(7)
    for size in (1, 2, 3, 9, 2 ** 20 + 5):
        buf = rng.integers(0, 256, size, dtype=np.uint8)
        for at in sorted({0, size // 2, size - 1}):
            new = buf.copy()
            new[at] ^= 1 << int(rng.integers(8))
            got = crc_after_change([zlib.crc32(buf.tobytes())], buf[None, at:at + 1],
                                   new[None, at:at + 1], size - at - 1)
            assert got.tolist() == [zlib.crc32(new.tobytes())], (size, at)
