"""UNET framing: CRC-16, byte-stuffed frames between flags, and a frame parser.

The Vision Machine's eye-head hangs off UNET, a multi-drop network of up to 32 micros under one host
master, where micros "only speak when spoken to" (Poggio et al., "The MIT Vision Machine", section
"The Eye-Head system"). The byte format here follows the proven serial protocols:

* Dynamixel Protocol 2.0: an id, a length, an instruction, a CRC-16, status packets that carry error
  bits, a broadcast id that is never answered, and byte stuffing so that a payload can never hold a
  header.
* HDLC / PPP (RFC 1662): a flag byte opens and closes every frame, and an escape byte hides the flag
  (and itself) inside the frame, so the flag on the wire only ever means a frame boundary.
* Modbus RTU: one-byte addresses, CRC-16/MODBUS sent low byte first, a slave that stays silent on a bad
  CRC so that the master times out and retries.

On the wire: ``A5 | stuffed(ADDR SEQ LEN body CRC16) | A5``; the body is ``CMD payload`` in a request
and ``STATUS CMD payload`` in a reply (ADDR with bit 7 set). Inside the flags every ``A5`` is sent as
``DB 85`` and every ``DB`` as ``DB FB``. LEN counts the body's bytes and must agree with the number of
bytes actually found between the flags; the CRC covers ADDR to the end of the payload. Because a payload
byte can never be ``A5``, no frame can ever be found inside another one. hardware/PROTOCOL.md is the
full specification.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "BROADCAST",
    "ESCAPE",
    "FLAG",
    "LONGEST_FRAME",
    "MAX_ADDRESS",
    "MAX_PAYLOAD",
    "REPLY_BIT",
    "Frame",
    "Parser",
    "crc16",
    "encode_reply",
    "encode_request",
]

FLAG = 0xA5
ESCAPE = 0xDB
# An escaped byte is sent as ESCAPE followed by the byte XOR this (as in HDLC), so neither FLAG nor
# ESCAPE ever follows an ESCAPE.
_FLIP = 0x20
_ESCAPED = {FLAG ^ _FLIP: FLAG, ESCAPE ^ _FLIP: ESCAPE}
BROADCAST = 0
MAX_ADDRESS = 31
REPLY_BIT = 0x80
MAX_PAYLOAD = 30
_HEADER = 3  # ADDR, SEQ, LEN
_CRC = 2
_MIN_CONTENT = _HEADER + 1 + _CRC  # the shortest request: no payload
_MAX_CONTENT = _HEADER + MAX_PAYLOAD + 2 + _CRC  # the longest reply
LONGEST_FRAME = _MAX_CONTENT + 2
"""The longest frame's bytes between and with its two flags, before stuffing (which at most doubles them)."""
# The fewest wire bytes that can complete a frame when none is under way: its content and a closing
# flag (the opening one may be the flag that closed the previous frame).
_SHORTEST_ON_WIRE = 1 + _MIN_CONTENT + 1


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


def _stuff(content: bytes | bytearray) -> bytes:
    # ESCAPE first, so that the escapes added for FLAG are not escaped again.
    return bytes(content).replace(b"\xdb", b"\xdb\xfb").replace(b"\xa5", b"\xdb\x85")


def _encode(addr_byte: int, seq: int, body: bytes) -> bytes:
    content = bytearray((addr_byte, seq, len(body)))
    content += body
    crc = crc16(content)
    content += bytes((crc & 0xFF, crc >> 8))
    return bytes((FLAG,)) + _stuff(content) + bytes((FLAG,))


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
    'a5 01 07 01 01 70 49 a5'
    >>> encode_request(1, 0xA5, 0x01).hex(" ")  # an A5 inside the frame is escaped
    'a5 01 db 85 01 01 d1 ab a5'
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
        return 1 <= addr <= MAX_ADDRESS and 2 <= length <= MAX_PAYLOAD + 2
    return addr_byte <= MAX_ADDRESS and 1 <= length <= MAX_PAYLOAD + 1


class Parser:
    """Incremental frame parser: every flag byte ends one candidate frame and begins the next.

    Feed it bytes as they arrive, in pieces of any size. The bytes between two flags are unstuffed and
    taken as a frame only if the escapes are well formed, the header is plausible, LEN equals the number
    of body bytes actually received, and the CRC checks; anything else is dropped whole. A flag can
    never occur inside a frame, so resynchronisation is immediate: a frame cut short is abandoned at the
    next flag, and the frame that flag opens is read normally. It never raises on any input.

    Attributes
    ----------
    dropped : int
        Bytes discarded: bytes before the first flag, and the bytes between the flags of every candidate
        that was refused.
    crc_errors : int
        Candidates with a plausible header and the length LEN announces whose CRC failed.
    """

    def __init__(self) -> None:
        self._content = bytearray()
        self._raw = 0  # wire bytes of the candidate under way, escapes included
        self._hunting = True  # before the first flag: bytes that belong to no frame we can see
        self._escaped = False
        self._bad = False
        self.dropped = 0
        self.crc_errors = 0

    def feed(self, data: bytes | bytearray) -> list[Frame]:
        """Append `data` and return the frames completed by it, in order."""
        frames = []
        for byte in data:
            if byte == FLAG:
                if self._hunting:
                    self._hunting = False
                elif self._raw:
                    frame = self._close()
                    if frame is not None:
                        frames.append(frame)
                continue
            if self._hunting:
                self.dropped += 1
                continue
            self._raw += 1
            if self._bad:
                continue
            if self._escaped:
                self._escaped = False
                if byte not in _ESCAPED:
                    self._bad = True
                    continue
                byte = _ESCAPED[byte]
            elif byte == ESCAPE:
                self._escaped = True
                continue
            if len(self._content) == _MAX_CONTENT:
                self._bad = True  # longer than any frame: stop keeping it
                continue
            self._content.append(byte)
        return frames

    def _close(self) -> Frame | None:
        content, raw = self._content, self._raw
        ok = not (self._bad or self._escaped) and _MIN_CONTENT <= len(content)
        ok = ok and _header_valid(content[0], content[2]) and content[2] == len(content) - _HEADER - _CRC
        if ok and crc16(memoryview(content)[:-_CRC]) != content[-2] | content[-1] << 8:
            self.crc_errors += 1
            ok = False
        frame = self._decode(content) if ok else None
        if not ok:
            self.dropped += raw
        self._content = bytearray()
        self._raw = 0
        self._escaped = self._bad = False
        return frame

    @staticmethod
    def _decode(content: bytearray) -> Frame:
        addr_byte, seq = content[0], content[1]
        body = bytes(content[_HEADER:-_CRC])
        if addr_byte & REPLY_BIT:
            return Frame(addr_byte & ~REPLY_BIT, seq, body[1], body[2:], body[0])
        return Frame(addr_byte, seq, body[0], body[1:])

    def bytes_needed(self) -> int:
        """The fewest further bytes that could complete a frame (at least 1): how much to read next,
        so that a blocking read never waits for more than the shortest frame that may be under way."""
        if self._hunting:
            return _SHORTEST_ON_WIRE
        content = self._content
        if self._bad:
            return _SHORTEST_ON_WIRE  # this candidate's closing flag, then a whole frame
        if len(content) < _HEADER:
            return _MIN_CONTENT - len(content) + 1
        if not _header_valid(content[0], content[2]):
            return _SHORTEST_ON_WIRE
        # The rest of this frame and its closing flag; or, if a flag ends it early, a whole frame.
        rest = _HEADER + content[2] + _CRC - len(content) + 1
        return max(1, min(rest, _SHORTEST_ON_WIRE))
