"""Per-message bit layouts compiled once from the cantools database: the frame hot path.

What it does: for one DBC message, turns physical signal values into the payload bytes
and back, exactly as cantools' ``Message.encode(values, scaling=True, strict=False)`` and
``Message.decode(data, decode_choices=False, scaling=True)`` do, without their per-call
generality (choices, multiplexing, containers, truncation, argument checks). The bit
positions, scale, offset and range of every signal are read from the cantools ``Signal``
objects, so the DBC stays the only place an ID, a position or a scale factor is written.

How: when every signal is a little-endian (Intel) integer field, as in ``thruster_hil.dbc``,
the payload is one little-endian integer and each signal a bit field of it, masked and
shifted with positions read from the cantools ``Signal`` (``start``, ``length``,
``is_signed``); otherwise (big-endian or IEEE-float signals) cantools' own compiled
``bitstruct`` formats (``cantools.database.utils.create_encode_decode_formats``) pack and
unpack. Both give cantools' bytes and values exactly.

In: a ``cantools`` ``Message`` (not multiplexed: every frame of ``thruster_hil.dbc``).
Out (:meth:`FrameLayout.pack`): an ``bytearray`` of the message's length, CRC and alive
counter bytes still to be written by :func:`dbc.e2e.protect`. In (:meth:`FrameLayout.unpack`):
payload bytes -> ``{signal: physical value}``, ints for unscaled integer signals as cantools
returns them. Range checks on encoding: a value outside the DBC's [minimum, maximum] raises
:class:`~dbc.errors.IcdError` naming the signal, the value and the range.

Conversions (cantools ``conversion.py``): identity and linear -> ``(v - offset) / scale``
(rounded half to even if integer; for identity, offset 0 and scale 1 give cantools' own
``round(v)``), and back ``raw * scale + offset`` (identity: the raw value itself); any
other conversion calls cantools' own method. The contract
test ``tests/dbc/test_layout.py`` checks byte-identical encoding and identical decoding
against cantools on random values and payloads of every message.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from cantools.database.can import Message
from cantools.database.conversion import IdentityConversion, LinearConversion
from cantools.database.utils import create_encode_decode_formats

from dbc.errors import IcdError

IDENTITY, LINEAR, OTHER = 0, 1, 2  # how a signal converts between raw and physical
_MISSING = object()  # pack_merged: a signal the signals mapping does not have


def _mode(signal: Any) -> int:
    conv = signal.conversion
    if type(conv) is IdentityConversion:
        return IDENTITY
    if type(conv) is LinearConversion:
        return LINEAR
    return OTHER


class FrameLayout:
    """Encode and decode one message's signals (see the module docstring)."""

    def __init__(self, message: Message) -> None:
        if message.is_multiplexed() or message.is_container:
            raise IcdError(f"message {message.name}: multiplexed or container frames unsupported")
        self.message = message
        self.name = message.name
        self.length = message.length
        formats = create_encode_decode_formats(message.signals, message.length)
        self._big = formats.big_endian
        self._little = formats.little_endian
        # bit fields of one little-endian integer, when every signal is one (see above)
        self._fields = all(s.byte_order == "little_endian" and not s.conversion.is_float
                           for s in message.signals)
        self._names = [str(s.name) for s in message.signals]
        self._shifts = [int(s.start) for s in message.signals]
        self._masks = [(1 << int(s.length)) - 1 for s in message.signals]
        self._sign_bits = [1 << (int(s.length) - 1) if s.is_signed else 0
                           for s in message.signals]
        self._modes = [_mode(s) for s in message.signals]
        inf = float("inf")
        # encoding: (name, lo, hi, scale, offset, to_int) for identity and linear signals
        # (identity = scale 1, offset 0, exactly), (name, lo, hi, conversion) for the others
        self._enc = tuple(
            (s.name, -inf if s.minimum is None else float(s.minimum),
             inf if s.maximum is None else float(s.maximum),
             s.conversion.scale, s.conversion.offset, not s.conversion.is_float)
            for s in message.signals if _mode(s) != OTHER
        )
        self._enc_other = tuple(
            (s.name, -inf if s.minimum is None else float(s.minimum),
             inf if s.maximum is None else float(s.maximum), s.conversion)
            for s in message.signals if _mode(s) == OTHER
        )
        # The encoder's typed view of the integer fields (pack_merged), in signal order:
        # range, and scale and offset as floats for Python numbers (identity: 1 and 0,
        # exactly cantools' round(v) below 2**53; no signal of the DBC is that wide), or
        # the conversion for the other kinds.
        signals = message.signals
        self._lo = [-inf if s.minimum is None else float(s.minimum) for s in signals]
        self._hi = [inf if s.maximum is None else float(s.maximum) for s in signals]
        self._scales = [float(s.conversion.scale) if _mode(s) != OTHER else 1.0
                        for s in signals]
        self._offsets = [float(s.conversion.offset) if _mode(s) != OTHER else 0.0
                         for s in signals]
        self._convs: list[Any] = [s.conversion for s in signals]
        # cantools' own scale and offset objects (decoding returns its types)
        self._dec_scales: list[Any] = [s.conversion.scale for s in signals]
        self._dec_offsets: list[Any] = [s.conversion.offset for s in signals]
        # decoding: (name, mode, scale, offset, conversion)
        self._dec = tuple(
            (s.name, _mode(s), s.conversion.scale, s.conversion.offset, s.conversion)
            for s in message.signals
        )

    def pack(self, values: Mapping[str, Any], source: Mapping[str, Any] | None = None) -> bytearray:
        """Payload carrying ``values`` (physical units; every signal of the message).

        ``source``: what to quote in an error (default ``values``).
        """
        if self._fields:
            return self._pack_fields({}, values, source)
        raw: dict[str, int | float] = {}
        try:
            for name, lo, hi, scale, offset, to_int in self._enc:
                v = values[name]
                if not lo <= v <= hi:
                    raise ValueError(name)
                r = (v - offset) / scale
                raw[name] = round(r) if to_int else r
            for name, lo, hi, conv in self._enc_other:
                v = values[name]
                if not lo <= v <= hi:
                    raise ValueError(name)
                raw[name] = conv.numeric_scaled_to_raw(v)
            packed = int.from_bytes(self._big.pack(raw), "big") | int.from_bytes(
                self._little.pack(raw), "little"
            )
        except Exception as exc:  # the slow path: say which value and why
            raise self._error(values, source, exc) from None
        return bytearray(packed.to_bytes(self.length, "big"))

    def pack_merged(self, base: Mapping[str, Any], signals: Mapping[str, Any]) -> bytearray:
        """``pack({**base, **signals}, signals)`` without building the merged mapping: the
        encoder's hot path (``base`` holds the E2E fields), on typed fields."""
        if not self._fields:
            merged = dict(base)
            merged.update(signals)
            return self.pack(merged, signals)
        return self._pack_fields(base, signals, signals)

    def _pack_fields(self, base: Mapping[str, Any], signals: Mapping[str, Any],
                     source: Mapping[str, Any] | None) -> bytearray:
        """``pack`` of ``{**base, **signals}`` for a message of little-endian integer fields
        only, on typed fields (``source``: what an error quotes)."""
        payload = 0
        given = signals if isinstance(signals, dict) else dict(signals)
        try:
            for i in range(len(self._names)):
                name = self._names[i]
                x = given.get(name, _MISSING)
                if x is _MISSING:
                    x = base[name]
                if self._modes[i] == OTHER:
                    if not self._lo[i] <= x <= self._hi[i]:
                        raise ValueError(name)
                    raw = int(self._convs[i].numeric_scaled_to_raw(x))
                elif type(x) is float or type(x) is int or type(x) is bool:
                    v: float = x + 0.0  # in C doubles: exactly pack's arithmetic for these
                    if not self._lo[i] <= v <= self._hi[i]:
                        raise ValueError(name)
                    raw = round((v - self._offsets[i]) / self._scales[i])
                else:  # numpy scalars keep their own arithmetic (float32), as in pack
                    if not self._lo[i] <= x <= self._hi[i]:
                        raise ValueError(name)
                    raw = round((x - self._dec_offsets[i]) / self._dec_scales[i])
                payload |= (raw & self._masks[i]) << self._shifts[i]
        except Exception as exc:  # the slow path: say which value and why
            merged = dict(base)
            merged.update(signals)
            raise self._error(merged, source, exc) from None
        return bytearray(payload.to_bytes(self.length, "little"))

    def _error(self, values: Mapping[str, Any], source: Mapping[str, Any] | None,
               exc: Exception) -> IcdError:
        """The IcdError for a ``pack`` that failed with ``exc``: the first bad signal."""
        quoted = values if source is None else source
        for name, lo, hi in [e[:3] for e in self._enc] + [e[:3] for e in self._enc_other]:
            v = values.get(str(name))
            try:
                bad = not lo <= v <= hi  # type: ignore[operator]
            except TypeError:  # missing or not a number
                bad = True
            if bad:
                return IcdError(f"cannot encode {self.name}: {name} = {v!r} outside "
                                f"[{lo}, {hi}] (or missing) in {quoted}")
        return IcdError(f"cannot encode {self.name} from {quoted}: {exc}")

    def unpack(self, data: bytes | bytearray) -> dict[str, Any]:
        """Physical signal values of a payload of exactly ``length`` bytes."""
        if self._fields:
            return self._unpack_fields(data)
        unpacked = {**self._big.unpack(data), **self._little.unpack(data[::-1])}
        return {name: _physical(unpacked[name], mode, scale, offset, conv)
                for name, mode, scale, offset, conv in self._dec}

    def _unpack_fields(self, data: bytes | bytearray) -> dict[str, Any]:
        """``unpack`` for a message of little-endian integer fields only."""
        payload = int.from_bytes(data, "little")
        out: dict[str, Any] = {}
        for i in range(len(self._names)):
            raw = (payload >> self._shifts[i]) & self._masks[i]
            sign = self._sign_bits[i]
            if raw & sign:
                raw -= sign << 1
            out[self._names[i]] = _physical(raw, self._modes[i], self._dec_scales[i],
                                            self._dec_offsets[i], self._convs[i])
        return out


def _physical(raw: Any, mode: int, scale: Any, offset: Any, conv: Any) -> Any:
    """A raw signal value in physical units, of cantools' type (ints stay ints unscaled)."""
    if mode == IDENTITY:
        return raw
    if mode == LINEAR:
        return raw * scale + offset
    return conv.raw_to_scaled(raw, False)
