"""What an LZ4 frame that was cut short still holds: every whole block, then the cut one.

A recorder that dies while writing an LZ4 chunk (a ``.bag`` chunk is one 1 MB roslz4 block;
MCAP chunks are LZ4 frames too) leaves a frame that ends inside a block. liblz4 decodes only
whole blocks, so it yields nothing of that one, yet the block's sequences up to the cut are
intact: decoding them by hand gives back the messages they hold.
"""

from __future__ import annotations

import lz4.block

MAGIC = 0x184D2204
#: LZ4 matches reach at most this far back, into earlier blocks when blocks are linked.
WINDOW = 65536
_INDEPENDENT = 0x20
_BLOCK_CHECKSUM = 0x10
_CONTENT_SIZE = 0x08
_DICT_ID = 0x01
_UNCOMPRESSED = 0x80000000


def salvage(data: bytes | memoryview, limit: int) -> bytes:
    """The decompressed prefix of the LZ4 frame ``data``, which may end anywhere; at most ``limit``.

    Raises ``ValueError`` when ``data`` is not an LZ4 frame or a block before the cut is corrupt.
    """
    view = memoryview(data)
    if len(view) >= 4 and int.from_bytes(view[:4], "little") != MAGIC:
        raise ValueError("not an LZ4 frame")
    if len(view) < 7:
        return b""
    flags, block_max_id = view[4], (view[5] >> 4) & 7
    if block_max_id < 4:
        raise ValueError(f"LZ4 frame has an invalid block size id {block_max_id}")
    block_max = 1 << (8 + 2 * block_max_id)  # 4: 64 KiB, 5: 256 KiB, 6: 1 MiB, 7: 4 MiB
    linked = not flags & _INDEPENDENT
    pos = 7 + (8 if flags & _CONTENT_SIZE else 0) + (4 if flags & _DICT_ID else 0)
    out = bytearray()
    while len(out) < limit and pos + 4 <= len(view):
        word = int.from_bytes(view[pos : pos + 4], "little")
        if word == 0:  # end mark
            break
        size = word & ~_UNCOMPRESSED
        block = view[pos + 4 : pos + 4 + size]
        pos += 4 + size + (4 if flags & _BLOCK_CHECKSUM else 0)
        history = bytes(out[-WINDOW:]) if linked else b""
        if word & _UNCOMPRESSED:
            out += block
        elif len(block) == size:
            try:
                out += lz4.block.decompress(block, uncompressed_size=block_max, dict=history)
            except lz4.block.LZ4BlockError as err:
                raise ValueError(f"LZ4 block does not decompress: {err}") from err
        else:
            out += decode_cut_block(block, history)
        if len(block) < size:
            break
    return bytes(out[:limit])


def decode_cut_block(src: bytes | memoryview, history: bytes = b"") -> bytes:
    """The bytes of an LZ4 block's sequences that lie wholly before the block's cut end.

    Literals are kept up to the cut; a match whose length or offset was cut off is dropped.
    ``history`` is what preceded the block (for linked blocks).
    """
    out = bytearray(history)
    start, i, n = len(out), 0, len(src)
    while i < n:
        token = src[i]
        i += 1
        literals, i, whole = _length(src, i, token >> 4)
        out += src[i : i + literals]
        i += literals
        if not whole or i + 2 > n:
            break
        offset = src[i] | src[i + 1] << 8
        i += 2
        extra, i, whole = _length(src, i, token & 15)
        if not whole:
            break
        if not 0 < offset <= len(out):
            raise ValueError(f"LZ4 block refers {offset} bytes back, before its start")
        _copy_match(out, offset, extra + 4)
    return bytes(out[start:])


def _length(src: bytes | memoryview, i: int, nibble: int) -> tuple[int, int, bool]:
    """A token nibble's length with its 255-run extension: (length, next index, complete)."""
    if nibble != 15:
        return nibble, i, True
    while i < len(src):
        byte = src[i]
        i += 1
        nibble += byte
        if byte != 255:
            return nibble, i, True
    return nibble, i, False


def _copy_match(out: bytearray, offset: int, length: int) -> None:
    """Append ``length`` bytes copied from ``offset`` back, overlapping as LZ4 allows."""
    pos = len(out) - offset
    if offset >= length:
        out += out[pos : pos + length]
        return
    pattern = bytes(out[pos:])  # the copy overlaps itself: it repeats the last ``offset`` bytes
    repeats, rest = divmod(length, offset)
    out += pattern * repeats + pattern[:rest]
