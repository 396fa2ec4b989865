"""UNET framing: CRC-16, frame encoding and a resynchronising frame parser.

The Vision Machine's eye-head hangs off UNET, a multi-drop network of up to 32 micros under one host
master, where micros "only speak when spoken to" (Poggio et al., "The MIT Vision Machine", section
"The Eye-Head system"). The byte format here follows the proven serial servo protocols:

* Dynamixel Protocol 2.0: a sync header, an id, a length, an instruction, a CRC-16, status packets that
  carry error bits, broadcast id that is never answered.
* Modbus RTU: one-byte addresses, CRC-16/MODBUS sent low byte first, a slave that stays silent on a bad
  CRC so that the master times out and retries.

Request ``A5 | ADDR | SEQ | LEN | CMD | payload | CRC16``, reply ``A5 | ADDR|0x80 | SEQ | LEN | STATUS |
CMD | payload | CRC16``. LEN counts the bytes between LEN and the CRC. The CRC covers everything from the
sync byte to the end of the body. hardware/PROTOCOL.md is the full specification.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "BROADCAST",
    "MAX_ADDRESS",
    "MAX_PAYLOAD",
    "REPLY_BIT",
    "SYNC",
    "Frame",
    "Parser",
    "crc16",
    "encode_reply",
    "encode_request",
]

SYNC = 0xA5
BROADCAST = 0
MAX_ADDRESS = 31
REPLY_BIT = 0x80
MAX_PAYLOAD = 30
_HEADER = 4
_CRC = 2
_MIN_REQUEST = _HEADER + 1 + _CRC
# A bound on LEN keeps a false sync byte in garbage from holding up the parser for long.
_MAX_BODY = MAX_PAYLOAD + 2


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_TABLE = _crc_table()


def crc16(data: bytes | bytearray | memoryview, crc: int = 0xFFFF) -> int:
    """CRC-16/MODBUS of `data`.

    Parameters
    ----------
    data : bytes-like
        The bytes to check.
    crc : int, optional
        The running value, to continue a CRC over several pieces.

    Returns
    -------
    int
        The 16-bit CRC. It goes on the wire low byte first, as in Modbus RTU.

    Notes
    -----
    Polynomial 0x8005 reflected (0xA001), initial value 0xFFFF, reflected in and out, no final XOR: the
    CRC-16/MODBUS of the CRC catalogue, whose check value (the CRC of ``b"123456789"``) is 0x4B37. It
    detects every error burst up to 16 bits long, so every single corrupted byte.

    Examples
    --------
    >>> hex(crc16(b"123456789"))
    '0x4b37'
    """
    table = _TABLE
    for byte in data:
        crc = (crc >> 8) ^ table[(crc ^ byte) & 0xFF]
    return crc


@dataclass(frozen=True)
class Frame:
    """One decoded frame.

    Attributes
    ----------
    addr : int
        The micro's address, 0 (broadcast) to 31, without the reply bit.
    seq : int
        Sequence number, 0..255; a reply carries the sequence number of its request.
    cmd : int
        Command code.
    payload : bytes
        Command arguments or reply data.
    status : int or None
        The reply's STATUS byte; None for a request.
    """

    addr: int
    seq: int
    cmd: int
    payload: bytes = b""
    status: int | None = None

    @property
    def is_reply(self) -> bool:
        """True for a reply (a frame sent by a micro)."""
        return self.status is not None


def _check_byte(name: str, value: int, low: int, high: int) -> None:
    if not isinstance(value, int) or isinstance(value, bool):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    if not low <= value <= high:
        raise ValueError(f"{name} must be in {low}..{high}, got {value}")


def _encode(addr_byte: int, seq: int, body: bytes) -> bytes:
    frame = bytearray((SYNC, addr_byte, seq, len(body)))
    frame += body
    crc = crc16(frame)
    frame += bytes((crc & 0xFF, crc >> 8))
    return bytes(frame)


def _check_frame_args(addr: int, seq: int, cmd: int, payload: bytes) -> None:
    _check_byte("addr", addr, 0, MAX_ADDRESS)
    _check_byte("seq", seq, 0, 255)
    _check_byte("cmd", cmd, 0, 255)
    if not isinstance(payload, (bytes, bytearray)):
        raise TypeError(f"payload must be bytes, got {type(payload).__name__}")
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"payload must be at most {MAX_PAYLOAD} bytes, got {len(payload)}")


def encode_request(addr: int, seq: int, cmd: int, payload: bytes = b"") -> bytes:
    """Encode a request from the host to micro `addr` (0 broadcasts to every micro, which never answer).

    Examples
    --------
    >>> encode_request(1, 7, 0x01).hex(" ")
    'a5 01 07 01 01 18 74'
    """
    _check_frame_args(addr, seq, cmd, payload)
    return _encode(addr, seq, bytes((cmd,)) + bytes(payload))


def encode_reply(addr: int, seq: int, status: int, cmd: int, payload: bytes = b"") -> bytes:
    """Encode the reply of micro `addr` to the request numbered `seq`."""
    _check_frame_args(addr, seq, cmd, payload)
    _check_byte("addr", addr, 1, MAX_ADDRESS)
    _check_byte("status", status, 0, 255)
    return _encode(addr | REPLY_BIT, seq, bytes((status, cmd)) + bytes(payload))


def _header_valid(addr_byte: int, length: int) -> bool:
    if addr_byte & REPLY_BIT:
        addr = addr_byte & ~REPLY_BIT
        return 1 <= addr <= MAX_ADDRESS and 2 <= length <= _MAX_BODY
    return addr_byte <= MAX_ADDRESS and 1 <= length <= MAX_PAYLOAD + 1


class Parser:
    """Incremental frame parser that resynchronises after garbage.

    Feed it bytes as they arrive, in pieces of any size; it returns each frame whose header is plausible
    and whose CRC checks. After a bad header or a bad CRC it drops only the sync byte and rescans from
    the next byte, so a real frame that follows garbage (or a frame cut short) is still found; a
    complete frame found beyond an incomplete one is taken at once (the incomplete one was garbage). It
    never raises on any input.

    Attributes
    ----------
    dropped : int
        Bytes discarded while hunting for a frame.
    crc_errors : int
        Candidate frames (plausible header, full length) whose CRC failed.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self.dropped = 0
        self.crc_errors = 0

    def feed(self, data: bytes | bytearray) -> list[Frame]:
        """Append `data` and return the frames completed by it, in order."""
        buf = self._buf
        buf += data
        frames = []
        while buf:
            start = buf.find(SYNC)
            if start < 0:
                self.dropped += len(buf)
                buf.clear()
                break
            if start:
                self.dropped += start
                del buf[:start]
            if len(buf) < _HEADER:
                break
            length = buf[3]
            if not _header_valid(buf[1], length):
                self._drop(1)
                continue
            end = _HEADER + length
            if len(buf) < end + _CRC:
                # A false sync byte in garbage can announce a body longer than what follows; a complete
                # frame further on proves it false, and need not wait for bytes that may never come.
                later = self._complete_frame_after(1)
                if later is None:
                    break
                self._drop(later)
                continue
            if not self._crc_ok(0, end):
                self.crc_errors += 1
                self._drop(1)
                continue
            frames.append(self._decode(end))
            del buf[: end + _CRC]
        return frames

    def _crc_ok(self, start: int, end: int) -> bool:
        buf = self._buf
        return crc16(memoryview(buf)[start:end]) == buf[end] | buf[end + 1] << 8

    def _complete_frame_after(self, first: int) -> int | None:
        buf = self._buf
        j = buf.find(SYNC, first)
        while 0 <= j <= len(buf) - _MIN_REQUEST:
            if _header_valid(buf[j + 1], buf[j + 3]):
                end = j + _HEADER + buf[j + 3]
                if end + _CRC <= len(buf) and self._crc_ok(j, end):
                    return j
            j = buf.find(SYNC, j + 1)
        return None

    def _decode(self, end: int) -> Frame:
        buf = self._buf
        addr_byte, seq = buf[1], buf[2]
        body = bytes(buf[_HEADER:end])
        if addr_byte & REPLY_BIT:
            return Frame(addr_byte & ~REPLY_BIT, seq, body[1], body[2:], body[0])
        return Frame(addr_byte, seq, body[0], body[1:])

    def _drop(self, count: int) -> None:
        self.dropped += count
        del self._buf[:count]

    def bytes_needed(self) -> int:
        """The fewest further bytes that could complete a frame (at least 1): how much to read next,
        so that a blocking read never waits for more than the shortest frame that may be under way."""
        buf = self._buf
        needs = []
        j = buf.find(SYNC)
        while j >= 0:
            have = len(buf) - j
            if have < _HEADER:
                needs.append(_MIN_REQUEST - have)
            elif _header_valid(buf[j + 1], buf[j + 3]):
                needs.append(_HEADER + buf[j + 3] + _CRC - have)
            j = buf.find(SYNC, j + 1)
        return max(1, min(needs, default=_MIN_REQUEST))
