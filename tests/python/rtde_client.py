# SPDX-License-Identifier: Apache-2.0
"""A small clean-room RTDE (port 30004) client for urtwin's tests.

Written from UR's "Real-Time Data Exchange (RTDE) Guide" and protocols.md §2 only: every package
is ``uint16 size (incl. the 3-byte header) | uint8 type | payload``, big-endian throughout.
It is deliberately strict, so that tests notice a server that bends the protocol:

* one reply per request, and the reply must be the very next package (like ur_rtde), unless the
  caller passes ``skip_other=True`` (like UR's own client and URCL, which skip other packages);
* reply lengths are checked (``V``/``S``/``P`` 1-byte payload, ``v`` exactly 16 bytes);
* type tokens must be exact; ``NOT_FOUND`` / ``IN_USE`` come back as :class:`RecipeError`.

Raw access (``send_raw``, ``recv_package``) is there for malformed-package tests.

Run ``python rtde_client.py`` to self-test the encoders against the worked example of
protocols.md §2.7a; ``python rtde_client.py HOST [PORT]`` prints a few packages of a live server.
"""

from __future__ import annotations

import socket
import struct
import sys
import time
from dataclasses import dataclass, field

V_REQUEST_PROTOCOL_VERSION = ord("V")
V_GET_URCONTROL_VERSION = ord("v")
M_TEXT_MESSAGE = ord("M")
U_DATA_PACKAGE = ord("U")
O_SETUP_OUTPUTS = ord("O")
I_SETUP_INPUTS = ord("I")
S_START = ord("S")
P_PAUSE = ord("P")

# type token -> struct format of one value (big-endian, no header)
TYPE_FORMATS = {
    "BOOL": "?",
    "UINT8": "B",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "DOUBLE": "d",
    "VECTOR3D": "3d",
    "VECTOR6D": "6d",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}

TEXT_LEVELS = {0: "EXCEPTION", 1: "ERROR", 2: "WARNING", 3: "INFO"}


class RtdeError(Exception):
    """The server broke the protocol (bad framing, wrong reply, refused request)."""


class RecipeError(RtdeError):
    """A setup reply named unknown (NOT_FOUND) or held (IN_USE) variables."""

    def __init__(self, message: str, names: list[str], types: list[str]):
        super().__init__(message)
        self.names = names
        self.types = types


# ---- pure encoders / decoders (no socket) -----------------------------------------------------


def pack_package(ptype: int, payload: bytes = b"") -> bytes:
    """Frame one package: size (header included), type, payload."""
    size = 3 + len(payload)
    if size > 0xFFFF:
        raise ValueError("package larger than 65535 bytes")
    return struct.pack(">HB", size, ptype) + payload


def encode_protocol_version(version: int) -> bytes:
    return pack_package(V_REQUEST_PROTOCOL_VERSION, struct.pack(">H", version))


def encode_get_version() -> bytes:
    return pack_package(V_GET_URCONTROL_VERSION)


def encode_setup_outputs(names: list[str], frequency: float | None) -> bytes:
    """O request; frequency is sent only with protocol 2 (pass None for protocol 1)."""
    text = ",".join(names).encode("ascii")
    head = b"" if frequency is None else struct.pack(">d", frequency)
    return pack_package(O_SETUP_OUTPUTS, head + text)


def encode_setup_inputs(names: list[str]) -> bytes:
    return pack_package(I_SETUP_INPUTS, ",".join(names).encode("ascii"))


def encode_start() -> bytes:
    return pack_package(S_START)


def encode_pause() -> bytes:
    return pack_package(P_PAUSE)


def encode_text_message(message: str, source: str = "urtwin-test", level: int = 3) -> bytes:
    """M from the client, in the length-prefixed layout of the guide (used by both versions)."""
    m = message.encode("ascii")[:255]
    s = source.encode("ascii")[:255]
    return pack_package(M_TEXT_MESSAGE, bytes([len(m)]) + m + bytes([len(s)]) + s + bytes([level]))


def values_format(types: list[str]) -> str:
    try:
        return ">" + "".join(TYPE_FORMATS[t] for t in types)
    except KeyError as e:
        raise RtdeError(f"unknown type token {e.args[0]!r}") from None


def encode_inputs(recipe_id: int, types: list[str], values: list) -> bytes:
    """U from the client: recipe id, then every value of the recipe in order."""
    flat: list = []
    for t, v in zip(types, values, strict=True):
        if TYPE_FORMATS[t][0].isdigit():
            flat.extend(v)
        else:
            flat.append(v)
    return pack_package(U_DATA_PACKAGE, bytes([recipe_id]) + struct.pack(values_format(types), *flat))


def decode_values(types: list[str], data: bytes) -> list:
    """Decode recipe values; vector types become tuples."""
    fmt = values_format(types)
    if struct.calcsize(fmt) != len(data):
        raise RtdeError(f"data is {len(data)} bytes, recipe needs {struct.calcsize(fmt)}")
    flat = struct.unpack(fmt, data)
    out, i = [], 0
    for t in types:
        f = TYPE_FORMATS[t]
        n = int(f[0]) if f[0].isdigit() else 1
        out.append(tuple(flat[i:i + n]) if f[0].isdigit() else flat[i])
        i += n
    return out


def split_packages(stream: bytes) -> tuple[list[tuple[int, bytes]], bytes]:
    """Split a byte stream into (type, payload) packages; returns them and the unparsed rest."""
    out, pos = [], 0
    while len(stream) - pos >= 3:
        size, ptype = struct.unpack_from(">HB", stream, pos)
        if size < 3:
            raise RtdeError(f"package size {size} < 3")
        if len(stream) - pos < size:
            break
        out.append((ptype, stream[pos + 3:pos + size]))
        pos += size
    return out, stream[pos:]


# ---- the client -------------------------------------------------------------------------------


@dataclass
class OutputRecipe:
    id: int                    # 0 with protocol 1 (no id on the wire)
    names: list[str]
    types: list[str]


@dataclass
class InputRecipe:
    id: int
    names: list[str]
    types: list[str]


@dataclass
class DataPackage:
    recipe_id: int | None      # None with protocol 1
    values: dict = field(default_factory=dict)
    received: float = 0.0      # time.monotonic() at decode


class RtdeClient:
    """A blocking RTDE client. Use as a context manager or call connect()/close()."""

    def __init__(self, host: str = "127.0.0.1", port: int = 30004, timeout: float = 2.0):
        self.host, self.port, self.timeout = host, port, timeout
        self.sock: socket.socket | None = None
        self.protocol = 1
        self.output: OutputRecipe | None = None
        self.inputs: dict[int, InputRecipe] = {}
        self.messages: list[tuple[str, str, int]] = []   # text messages seen (message, source, level)
        self._buf = b""

    # connection

    def connect(self) -> "RtdeClient":
        self.sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return self

    def close(self) -> None:
        if self.sock:
            self.sock.close()
            self.sock = None

    def __enter__(self):
        return self.connect() if self.sock is None else self

    def __exit__(self, *exc):
        self.close()

    # raw access

    def send_raw(self, data: bytes) -> None:
        assert self.sock is not None, "not connected"
        self.sock.sendall(data)

    def recv_package(self, timeout: float | None = None) -> tuple[int, bytes]:
        """The next whole package (type, payload). Raises TimeoutError or RtdeError on EOF."""
        assert self.sock is not None, "not connected"
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            if len(self._buf) >= 3:
                size, ptype = struct.unpack_from(">HB", self._buf)
                if size < 3:
                    raise RtdeError(f"server sent package size {size}")
                if len(self._buf) >= size:
                    payload, self._buf = self._buf[3:size], self._buf[size:]
                    return ptype, payload
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no complete RTDE package in time")
            self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                raise TimeoutError("no complete RTDE package in time") from None
            if not chunk:
                raise RtdeError("server closed the connection")
            self._buf += chunk

    def _request(self, data: bytes, reply_type: int, skip_other: bool) -> bytes:
        self.send_raw(data)
        while True:
            ptype, payload = self.recv_package()
            if ptype == reply_type:
                return payload
            if ptype == M_TEXT_MESSAGE:
                self.messages.append(self._decode_text(payload))
            if not skip_other:
                raise RtdeError(f"expected reply {chr(reply_type)!r}, got {chr(ptype)!r} "
                                f"({len(payload)} bytes)")

    def _decode_text(self, payload: bytes) -> tuple[str, str, int]:
        if self.protocol == 1:
            level = payload[0] if payload else 0
            return payload[1:].decode("ascii", "replace"), "", level
        n = payload[0]
        msg = payload[1:1 + n]
        k = payload[1 + n]
        src = payload[2 + n:2 + n + k]
        return msg.decode("ascii", "replace"), src.decode("ascii", "replace"), payload[2 + n + k]

    # setup phase

    def negotiate_protocol_version(self, version: int = 2, skip_other: bool = False) -> bool:
        payload = self._request(encode_protocol_version(version), V_REQUEST_PROTOCOL_VERSION,
                                skip_other)
        if len(payload) != 1:
            raise RtdeError(f"V reply payload is {len(payload)} bytes, want 1")
        if payload[0] == 1:
            self.protocol = version
        return payload[0] == 1

    def get_controller_version(self, skip_other: bool = False) -> tuple[int, int, int, int]:
        payload = self._request(encode_get_version(), V_GET_URCONTROL_VERSION, skip_other)
        if len(payload) != 16:
            raise RtdeError(f"v reply payload is {len(payload)} bytes, want 16")
        return struct.unpack(">IIII", payload)

    def _check_types(self, names: list[str], text: bytes, what: str) -> list[str]:
        types = text.decode("ascii").split(",") if text else []
        if len(types) != len(names):
            raise RtdeError(f"{what}: {len(types)} types for {len(names)} names: {text!r}")
        bad = [(n, t) for n, t in zip(names, types) if t not in TYPE_FORMATS]
        if bad:
            raise RecipeError(f"{what}: " + ", ".join(f"{n}={t}" for n, t in bad), names, types)
        return types

    def setup_outputs(self, names: list[str], frequency: float = 125.0,
                      skip_other: bool = False) -> OutputRecipe:
        freq = frequency if self.protocol == 2 else None
        payload = self._request(encode_setup_outputs(names, freq), O_SETUP_OUTPUTS, skip_other)
        if self.protocol == 2:
            rid, text = payload[0], payload[1:]
        else:
            rid, text = 0, payload
        types = self._check_types(names, text, "setup outputs")
        if self.protocol == 2 and rid == 0:
            raise RtdeError("setup outputs: server returned recipe id 0 (recipe refused)")
        self.output = OutputRecipe(rid, list(names), types)
        return self.output

    def setup_inputs(self, names: list[str], skip_other: bool = False) -> InputRecipe:
        payload = self._request(encode_setup_inputs(names), I_SETUP_INPUTS, skip_other)
        if not payload:
            raise RtdeError("setup inputs: empty reply")
        rid, text = payload[0], payload[1:]
        types = self._check_types(names, text, "setup inputs")
        if rid == 0:
            raise RtdeError("setup inputs: server returned recipe id 0 (recipe refused)")
        recipe = InputRecipe(rid, list(names), types)
        self.inputs[rid] = recipe
        return recipe

    def start(self, skip_other: bool = False) -> bool:
        payload = self._request(encode_start(), S_START, skip_other)
        if len(payload) != 1:
            raise RtdeError(f"S reply payload is {len(payload)} bytes, want 1")
        return payload[0] == 1

    def pause(self, skip_other: bool = True) -> bool:
        """P; data packages still in flight are skipped (as URCL does)."""
        self.send_raw(encode_pause())
        while True:
            ptype, payload = self.recv_package()
            if ptype == P_PAUSE:
                if len(payload) != 1:
                    raise RtdeError(f"P reply payload is {len(payload)} bytes, want 1")
                return payload[0] == 1
            if ptype != U_DATA_PACKAGE and not skip_other:
                raise RtdeError(f"expected 'P', got {chr(ptype)!r}")

    def send_message(self, message: str, source: str = "urtwin-test", level: int = 3) -> None:
        self.send_raw(encode_text_message(message, source, level))

    # synchronisation loop

    def receive(self, timeout: float | None = None) -> DataPackage:
        """The next data package, decoded with the output recipe. Text messages are recorded."""
        assert self.output is not None, "setup_outputs first"
        while True:
            ptype, payload = self.recv_package(timeout)
            if ptype == M_TEXT_MESSAGE:
                self.messages.append(self._decode_text(payload))
                continue
            if ptype != U_DATA_PACKAGE:
                raise RtdeError(f"expected a data package, got {chr(ptype)!r}")
            rid = None
            if self.protocol == 2:
                rid, payload = payload[0], payload[1:]
                if rid != self.output.id:
                    raise RtdeError(f"data package for recipe {rid}, ours is {self.output.id}")
            values = decode_values(self.output.types, payload)
            return DataPackage(rid, dict(zip(self.output.names, values)), time.monotonic())

    def send_inputs(self, recipe: InputRecipe, values: dict) -> None:
        """U for an input recipe; every variable of the recipe must be given."""
        missing = [n for n in recipe.names if n not in values]
        if missing:
            raise KeyError(f"values missing for {missing}")
        self.send_raw(encode_inputs(recipe.id, recipe.types, [values[n] for n in recipe.names]))


# ---- self-test against protocols.md §2.7a -----------------------------------------------------


def selftest() -> None:
    h = bytes.fromhex
    assert encode_protocol_version(2) == h("0005560002")
    assert encode_get_version() == h("000376")
    assert encode_setup_outputs(["timestamp", "actual_q"], 500.0) == \
        h("001D4F407F400000000000") + b"timestamp,actual_q"
    assert encode_setup_inputs(["speed_slider_mask", "speed_slider_fraction"]) == \
        h("002A49") + b"speed_slider_mask,speed_slider_fraction"
    assert encode_start() == h("000353")
    assert encode_pause() == h("000350")
    assert encode_inputs(1, ["UINT32", "DOUBLE"], [1, 0.5]) == \
        h("0010550100000001" "3FE0000000000000")

    # server side of the example, decoded
    server = (h("00045601") + h("001376" "00000005" "00000013" "00000000" "00127907")
              + h("00134F01") + b"DOUBLE,VECTOR6D" + h("00114901") + b"UINT32,DOUBLE"
              + h("00045301"))
    pk, rest = split_packages(server)
    assert rest == b""
    assert [chr(t) for t, _ in pk] == ["V", "v", "O", "I", "S"]
    assert struct.unpack(">IIII", pk[1][1]) == (5, 19, 0, 1210631)
    assert pk[2][1][1:] == b"DOUBLE,VECTOR6D"
    data = struct.pack(">d6d", 42.5, 0, 0.1, 0.2, 0.3, 0.4, 0.5)
    assert len(pack_package(U_DATA_PACKAGE, b"\x01" + data)) == 60
    assert decode_values(["DOUBLE", "VECTOR6D"], data) == [42.5, (0, 0.1, 0.2, 0.3, 0.4, 0.5)]
    assert decode_values(["BOOL", "UINT8", "INT32", "VECTOR3D", "VECTOR6INT32"],
                         struct.pack(">?Bi3d6i", True, 7, -3, 1, 2, 3, 1, 2, 3, 4, 5, 253)) == \
        [True, 7, -3, (1.0, 2.0, 3.0), (1, 2, 3, 4, 5, 253)]
    try:
        values_format(["NOT_FOUND"])
    except RtdeError:
        pass
    else:
        raise AssertionError("NOT_FOUND must not decode")


def _demo(host: str, port: int) -> None:
    with RtdeClient(host, port) as c:
        print("protocol 2:", c.negotiate_protocol_version(2))
        print("version:", c.get_controller_version())
        c.setup_outputs(["timestamp", "actual_q", "robot_mode", "runtime_state"], 125.0)
        print("start:", c.start())
        for _ in range(5):
            print(c.receive().values)
        print("pause:", c.pause())


if __name__ == "__main__":
    if len(sys.argv) > 1:
        _demo(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 30004)
    else:
        selftest()
        print("rtde_client self-test OK")
