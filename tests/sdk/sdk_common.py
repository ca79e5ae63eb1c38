"""Helpers shared by sdk_vectors.py and sdk_drive_sim.py (botbench's own code, not the SDK's).

The servo vendor's Python SDK (PyPI `fashionstar-uart-sdk`, MIT licence) is imported from the
virtual environment the scripts run in; nothing of it is copied here. Frame layout (seed 002):
request `12 4C cmd n content[n] sum`, reply `05 1C cmd n content[n] sum`, sum = every byte before
it mod 256.
"""

import importlib.metadata
import json
import logging
import platform
import sys
import warnings

sys.dont_write_bytecode = True

REQUEST_HEADER = b"\x12\x4c"
REPLY_HEADER = b"\x05\x1c"

# The units the SDK keeps in UartServoInfo (uservo.py), by attribute.
INFO_UNITS = {
    "cur_angle": "deg",
    "target_angle": "deg",
    "angle_monitor": "deg",
    "voltage": "mV",
    "current": "mA",
    "power": "mW",
    "temp": "degC (SDK's NTC conversion of the raw reading)",
    "status": "raw status byte",
    "turn": "turns",
}

# The UartServoInfo attributes worth reporting, in order.
INFO_FIELDS = [
    "is_online",
    "cur_angle",
    "target_angle",
    "is_mturn",
    "voltage",
    "current",
    "power",
    "temp",
    "status",
    "angle_monitor",
    "turn",
    "data_write_success",
]


def frame(header, cmd, content):
    """A frame's bytes: header, command, length, content, sum8 checksum."""
    body = header + bytes([cmd, len(content)]) + bytes(content)
    return body + bytes([sum(body) % 256])


def reply_frame(cmd, content):
    """A reply frame (05 1C) as a servo sends it."""
    return frame(REPLY_HEADER, cmd, content)


def split_frames(data, header):
    """Frames of one header found in `data`, in order: a list of (cmd, content, bytes).

    Bytes that are not a whole frame with a good checksum are skipped one at a time."""
    out = []
    i = 0
    while i + 5 <= len(data):
        if data[i : i + 2] != header:
            i += 1
            continue
        n = data[i + 3]
        end = i + 5 + n
        if end > len(data) or sum(data[i : end - 1]) % 256 != data[end - 1]:
            i += 1
            continue
        out.append((data[i + 2], bytes(data[i + 4 : end - 1]), bytes(data[i:end])))
        i = end
    return out


def frames_json(data, header):
    """[{"cmd": n, "hex": "..."}] for the frames of one header in `data`."""
    return [{"cmd": c, "hex": b.hex()} for c, _, b in split_frames(data, header)]


def writes_json(writes):
    """Each write the SDK made: its command (None if it is not one whole request frame) and hex."""
    out = []
    for w in writes:
        f = split_frames(w, REQUEST_HEADER)
        cmd = f[0][0] if len(f) == 1 and len(f[0][2]) == len(w) else None
        out.append({"cmd": cmd, "hex": bytes(w).hex()})
    return out


def info_json(info, diff_only=False):
    """A UartServoInfo as a dict (SDK units, see INFO_UNITS).

    With diff_only, only the attributes that differ from a fresh UartServoInfo of that id."""
    from fashionstar_uart_sdk.uservo import UartServoInfo

    fresh = UartServoInfo(info.id)
    out = {"id": info.id}
    for name in INFO_FIELDS:
        v = getattr(info, name, None)
        if diff_only and v == getattr(fresh, name, None):
            continue
        out[name] = jsonable(v)
    raw = getattr(info, "data_table_raw_dict", {})
    if raw:
        out["data_table_raw_dict"] = {str(k): bytes(v).hex() for k, v in sorted(raw.items())}
    return out


def jsonable(v):
    """A JSON-ready form of what the SDK returns: bytes become {"hex"}, servo records dicts."""
    from fashionstar_uart_sdk.uart_pocket_handler import Monitor_data, SyncPositionControlOptions
    from fashionstar_uart_sdk.uservo import UartServoInfo

    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (bytes, bytearray)):
        return {"hex": bytes(v).hex()}
    if isinstance(v, UartServoInfo):
        return info_json(v)
    if isinstance(v, (Monitor_data, SyncPositionControlOptions)):
        return {k: jsonable(x) for k, x in vars(v).items()}
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    return repr(v)


def servos_state(manager):
    """What the SDK has recorded about each servo it heard of (changed attributes only)."""
    out = {}
    for sid, info in sorted(getattr(manager, "servos", {}).items()):
        d = info_json(info, diff_only=True)
        if len(d) > 1:
            out[str(sid)] = d
    return out


def sdk_versions():
    """Versions of the SDK, pyserial and Python in use."""
    return {
        "sdk": "fashionstar-uart-sdk",
        "version": importlib.metadata.version("fashionstar-uart-sdk"),
        "pyserial": importlib.metadata.version("pyserial"),
        "python": platform.python_version(),
    }


class Captured:
    """Collects the SDK's log records (it logs to the root logger) and Python warnings."""

    def __init__(self):
        self.logs = []
        self.warnings = []
        self._handler = logging.Handler(logging.WARNING)
        self._handler.emit = lambda r: self.logs.append(f"{r.levelname}: {r.getMessage()}")
        self._ctx = None

    def __enter__(self):
        logging.getLogger().addHandler(self._handler)
        logging.getLogger().setLevel(logging.WARNING)
        self._ctx = warnings.catch_warnings(record=True)
        self._caught = self._ctx.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self.warnings = [f"{w.category.__name__}: {w.message}" for w in self._caught]
        self._ctx.__exit__(*exc)
        logging.getLogger().removeHandler(self._handler)
        return False


def call(fn):
    """Runs fn(); returns (value, error string or None)."""
    try:
        return fn(), None
    except Exception as e:  # the SDK raises many kinds; each is recorded, not fatal
        kind = type(e).__name__
        if type(e).__module__ != "builtins":
            kind = f"{type(e).__module__}.{kind}"
        return None, f"{kind}: {e}"


def open_port_handler(make_serial, port_name, baudrate):
    """A PortHandler opened through its own openPort(), with `make_serial(**kwargs)` standing in
    for serial.Serial. Returns (handler, the kwargs openPort passed)."""
    import types

    import serial
    from fashionstar_uart_sdk import uart_pocket_handler

    opened = {}

    def ctor(**kw):
        opened.update(kw)
        return make_serial(**kw)

    uart_pocket_handler.serial = types.SimpleNamespace(
        Serial=ctor, PARITY_NONE=serial.PARITY_NONE, SerialException=serial.SerialException
    )
    handler = uart_pocket_handler.PortHandler(port_name, baudrate)
    handler.openPort()
    return handler, opened


def emit(doc, out=sys.stdout):
    """Prints one JSON document on one line (keys in insertion order, UTF-8)."""
    out.write(json.dumps(doc, ensure_ascii=False) + "\n")
    out.flush()
