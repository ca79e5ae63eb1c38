#!/usr/bin/env python3
"""Byte vectors from the servo vendor's Python SDK (PyPI fashionstar-uart-sdk).

Drives every public operation of the SDK's servo API against an in-memory fake serial port on
which a small fake servo bus answers the way a servo does, and prints one JSON document a line:
the operation, its arguments, the exact bytes the SDK wrote, the replies, and what the SDK made of
them (return value and the per-servo record it keeps, in the SDK's own units). No hardware, no
pty, no wall clock: the SDK's `time` is a fake clock, so the output is the same on every run.

    /work/sdk-venv/bin/python tests/sdk/sdk_vectors.py > tests/sdk/vectors.jsonl

The line format and the SDK's conversions are described in tests/sdk/README.md.
"""

import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from sdk_common import (  # noqa: E402
    INFO_UNITS,
    REPLY_HEADER,
    Captured,
    call,
    emit,
    frames_json,
    jsonable,
    open_port_handler,
    reply_frame,
    sdk_versions,
    servos_state,
    split_frames,
    writes_json,
)

from fashionstar_uart_sdk import uart_pocket_handler, uservo  # noqa: E402
from fashionstar_uart_sdk.uart_pocket_handler import SyncPositionControlOptions  # noqa: E402
from fashionstar_uart_sdk.uservo import UartServoManager  # noqa: E402

# The fake servo answers this long after a request (the vendor's servos take 0.2-1 ms).
LATENCY_S = 0.0005
# Each call of the fake clock's time() moves it on by this much: the SDK's busy-wait loops end.
TICK_S = 0.001
# The FTDI latency timer's default: the second burst of a split reply comes this much later.
BURST_GAP_S = 0.016
# The angle a servo sends in MONITOR when it has no valid reading; the SDK skips such a reply.
MONITOR_NO_DATA_ANGLE = -235929599


class FakeClock:
    """Stands in for the `time` module inside the SDK."""

    def __init__(self):
        self.now = 1000.0
        self.slept = 0.0

    def time(self):
        t = self.now
        self.now += TICK_S
        return t

    def sleep(self, s):
        self.slept += s
        self.now += s


# Parameter widths and values of a fake servo (seed 002 read-only 1-8, user 32-53).
PARAM_FORMATS = {
    1: "<H", 2: "<H", 3: "<H", 4: "<H", 5: "<B", 6: "<H", 7: "<H", 8: "<I",
    32: "<B", 33: "<B", 34: "<B", 35: "<B", 36: "<B", 37: "<B", 38: "<H", 39: "<H", 40: "<H",
    41: "<H", 42: "<H", 43: "<H", 44: "<B", 45: "<B", 46: "<B", 47: "<B", 48: "<B", 49: "<B",
    50: "<H", 51: "<h", 52: "<h", 53: "<h",
}  # fmt: skip


class FakeServo:
    """One servo on the fake bus. Angles in 0.1 deg as on the wire; temp_raw is the 12-bit
    thermistor reading the SDK expects in both parameter 4 and MONITOR."""

    def __init__(self, sid, angle=0, mturn_angle=None, turns=0, temp_raw=2048, **kw):
        self.id = sid
        self.angle = angle
        self.mturn_angle = angle if mturn_angle is None else mturn_angle
        self.turns = turns
        self.voltage = kw.get("voltage", 7400)
        self.current = kw.get("current", 120)
        self.power = kw.get("power", 888)
        self.temp_raw = temp_raw
        self.status = kw.get("status", 0x01)
        self.write_result = kw.get("write_result", 1)
        self.monitor_no_data = kw.get("monitor_no_data", False)
        self.params = {
            6: 0x0101, 7: 0x0203, 8: 1000 + sid, 32: 0, 33: 0, 34: sid, 35: 0, 36: 5, 37: 1,
            38: 4000, 39: 4500, 40: 14000, 41: 65, 42: 12000, 43: 3000, 44: 1, 45: 0, 46: 0,
            47: 0, 48: 0, 49: 0, 50: 3000, 51: 1800, 52: -1800, 53: 0,
        }  # fmt: skip

    def param(self, pid):
        live = {1: self.voltage, 2: self.current, 3: self.power, 4: self.temp_raw, 5: self.status}
        v = live.get(pid, self.params.get(pid))
        return None if v is None else struct.pack(PARAM_FORMATS[pid], v)

    def monitor(self):
        angle, turns = (MONITOR_NO_DATA_ANGLE, 0) if self.monitor_no_data else (
            self.mturn_angle, self.turns)
        return struct.pack("<BHHHHBih", self.id, self.voltage, self.current, self.power,
                           self.temp_raw, self.status, angle, turns)

    def answer(self, cmd, c):
        """The reply frames to request (cmd, content), or []."""
        sid = self.id
        if cmd == 1 and len(c) == 1:
            return [reply_frame(1, [sid])]
        if cmd == 2 and len(c) == 1:
            return [reply_frame(2, [sid, 1])]
        if cmd == 3 and len(c) == 2:
            v = self.param(c[1])
            return [] if v is None else [reply_frame(3, bytes([sid, c[1]]) + v)]
        if cmd == 4 and len(c) >= 2:
            ok = self.write_result == 1 and c[1] in PARAM_FORMATS and c[1] >= 32
            if ok and c[1] == 34:
                self.id = c[2]  # answers from its new id (PROTOCOL_NOTES section 2)
            return [reply_frame(4, [self.id, c[1], 1 if ok else 0])]
        if cmd == 5 and len(c) == 1:
            block = b"".join(self.param(p) for p in range(32, 54))
            return [reply_frame(5, bytes([sid]) + block)]
        if cmd == 10 and len(c) == 1:
            return [reply_frame(10, struct.pack("<Bh", sid, self.angle))]
        if cmd == 16 and len(c) == 1:
            return [reply_frame(16, struct.pack("<Bih", sid, self.mturn_angle, self.turns))]
        if cmd == 22 and len(c) == 1:
            return [reply_frame(22, self.monitor())]
        return []  # motion commands answer only with response_switch on (it is off)


class FakeBus:
    """Servos on one line. Synchronous command 25 with sub-command 22 is answered by each listed
    servo in turn with its own MONITOR (cmd 22) reply."""

    def __init__(self, servos):
        self.servos = servos

    def answer(self, request):
        out = []
        for cmd, c, _ in split_frames(request, b"\x12\x4c"):
            if cmd == 25 and len(c) >= 3 and c[0] == 22 and c[1] == 1:
                for sid in c[3 : 3 + c[2]]:
                    out += [reply_frame(22, s.monitor()) for s in self.servos if s.id == sid]
                continue
            if cmd in (18, 19) or not c:
                continue
            for s in self.servos:
                if s.id == c[0]:
                    out += s.answer(cmd, c)
        return out


class FakeSerial:
    """An in-memory serial port: what the SDK writes goes to the bus; the bus's replies become
    readable LATENCY_S later on the fake clock. `echo` plays a one-wire bus (the request comes
    back first); `split_at` delivers each reply in two bursts BURST_GAP_S apart."""

    def __init__(self, bus, clock, echo=False, split_at=None):
        self.bus, self.clock, self.echo, self.split_at = bus, clock, echo, split_at
        self.writes, self.replies, self.rx_log = [], [], []
        self.pending = []  # [arrival time, bytearray]
        self.is_open = True
        self.t0 = clock.now

    def _arrive(self, at, data):
        self.pending.append([at, bytearray(data)])
        self.rx_log.append({"t_ms": round((at - self.t0) * 1000, 3), "hex": bytes(data).hex()})

    def write(self, data):
        data = bytes(data)
        self.writes.append(data)
        now = self.clock.now
        if self.echo:
            self._arrive(now, data)
        for r in self.bus.answer(data):
            self.replies.append(r)
            if self.split_at:
                self._arrive(now + LATENCY_S, r[: self.split_at])
                self._arrive(now + LATENCY_S + BURST_GAP_S, r[self.split_at :])
            else:
                self._arrive(now + LATENCY_S, r)
        return len(data)

    @property
    def in_waiting(self):
        return sum(len(b) for at, b in self.pending if at <= self.clock.now)

    def read(self, size=1):
        out = bytearray()
        while self.pending and len(out) < size and self.pending[0][0] <= self.clock.now:
            chunk = self.pending[0][1]
            take = min(size - len(out), len(chunk))
            out += chunk[:take]
            del chunk[:take]
            if not chunk:
                self.pending.pop(0)
        return bytes(out)

    def unread(self):
        return b"".join(bytes(b) for _, b in self.pending)

    def flush(self):
        pass

    def close(self):
        self.is_open = False


def servo_bus(*ids, over=None):
    """Fake servos with these ids: angle -45.6 deg, multi-turn 1234.5 deg in turn 3, temp 25 C;
    `over` maps an id to keyword overrides."""
    return FakeBus([FakeServo(i, angle=-456, mturn_angle=12345, turns=3, **(over or {}).get(i, {}))
                    for i in ids])


def sync_data(fmt, rows):
    """Per-servo records of a synchronous command, packed as a caller of the SDK packs them."""
    return [struct.pack(fmt, *r) for r in rows]


def bytes_args(args):
    """Arguments as JSON: bytes become hex, option records dicts."""
    return {k: (v.hex() if isinstance(v, (bytes, bytearray)) else
                [x.hex() for x in v] if isinstance(v, list) and v and isinstance(v[0], bytes)
                else jsonable(v)) for k, v in args.items()}


def run_case(case, clock):
    """Runs one case; returns its JSON document."""
    bus = case.get("bus") or servo_bus(1, 2, 3)
    port = FakeSerial(bus, clock, echo=case.get("echo", False), split_at=case.get("split_at"))
    api = case.get("api", "UartServoManager")
    opened = {}
    if api == "PortHandler":
        obj, opened = open_port_handler(lambda **kw: port, "fake", 115200)
    else:
        obj = UartServoManager(port)
    for setup in case.get("setup", []):
        getattr(obj, setup[0])(**setup[1])
    bus.servos = [s for s in bus.servos if s.id not in case.get("unplug", [])]
    n_writes, n_replies = len(port.writes), len(port.replies)
    slept0 = clock.slept
    args = case.get("args", {})
    with Captured() as cap:
        value, error = call(lambda: getattr(obj, case["method"])(**args))
    doc = {
        "kind": "op",
        "name": case["name"],
        "api": api,
        "method": case["method"],
        "args": case.get("args_json") or bytes_args(args),
    }
    if case.get("setup"):
        doc["setup"] = {
            "calls": [{"method": m, "args": bytes_args(a)} for m, a in case["setup"]],
            "requests": writes_json(port.writes[:n_writes]),
            "replies": [{"cmd": r[2], "hex": r.hex()} for r in port.replies[:n_replies]],
        }
    doc["requests"] = writes_json(port.writes[n_writes:])
    doc["replies"] = [{"cmd": r[2], "hex": r.hex()} for r in port.replies[n_replies:]]
    if case.get("echo") or case.get("split_at"):
        doc["rx"] = port.rx_log
    unread = port.unread()
    if unread:
        doc["unread"] = {"hex": unread.hex(), "frames": frames_json(unread, REPLY_HEADER)}
    doc["returned"] = jsonable(value)
    if "unit" in case:
        doc["returned_unit"] = case["unit"]
    doc["error"] = error
    doc["sdk_state"] = servos_state(obj)
    if case["method"] == "openPort":
        doc["serial_open"] = {k: jsonable(v) for k, v in opened.items()}
    if clock.slept - slept0 > 0:
        doc["slept_s"] = round(clock.slept - slept0, 6)
    if cap.logs:
        doc["log"] = cap.logs
    if cap.warnings:
        doc["warnings"] = cap.warnings
    if "note" in case:
        doc["note"] = case["note"]
    return doc


def temperature_cases():
    """Parameter 4 and MONITOR temperature for raw thermistor readings across the range."""
    out = []
    for raw in (32, 500, 1000, 1500, 2048, 2500, 3000, 3500, 4000, 4095, 0, 4096, 5000):
        bus = servo_bus(1, over={1: {"temp_raw": raw}})
        out.append({"name": f"query_temperature/raw_{raw}", "method": "query_temperature",
                    "args": {"servo_id": 1}, "bus": bus, "unit": "degC"})
    for raw in (32, 1000, 2048, 3000, 0, 4096, 5000):
        bus = servo_bus(1, over={1: {"temp_raw": raw}})
        out.append({"name": f"query_servo_monitor/temp_raw_{raw}", "method": "query_servo_monitor",
                    "args": {"servo_id": 1}, "bus": bus})
    return out


def set_angle_cases():
    """set_servo_angle in every branch (commands 8, 10+8, 11, 12, 13, 10+13, 14, 15), with the
    SDK's clamps."""
    rows = [
        ("by_interval", dict(angle=90.5, interval=500), "cmd 11 (interval given, single turn)"),
        ("by_interval_acc_dec_power",
         dict(angle=-90.5, interval=1500, t_acc=100, t_dec=150, power=3000), "cmd 11"),
        ("by_velocity", dict(angle=-45.67, velocity=200), "cmd 12; -456.7 truncates to -456"),
        ("by_velocity_acc_dec_power",
         dict(angle=120.0, velocity=55.55, t_acc=250, t_dec=80, power=2000), "cmd 12"),
        ("interval_zero", dict(angle=30.0, interval=0), "cmd 8 (interval 0 is not 'given')"),
        ("mean_dps", dict(angle=30.0), "cmd 10 then cmd 8; interval = |30 - (-45.6)| / 100 dps"),
        ("mean_dps_200", dict(angle=30.0, mean_dps=200.0), "cmd 10 then cmd 8"),
        ("mturn_interval_zero", dict(angle=720.5, is_mturn=True, interval=0), "cmd 13"),
        ("mturn_mean_dps", dict(angle=720.5, is_mturn=True),
         "cmd 10 (single-turn read) then cmd 13"),
        ("mturn_by_interval",
         dict(angle=-1080.3, is_mturn=True, interval=3000, t_acc=200, t_dec=300, power=5000),
         "cmd 14"),
        ("mturn_by_interval_defaults", dict(angle=3600.0, is_mturn=True, interval=1000),
         "cmd 14 with t_acc = t_dec = 20"),
        ("mturn_by_velocity", dict(angle=3600.0, is_mturn=True, velocity=100.5), "cmd 15"),
        ("mturn_by_velocity_acc_dec_power",
         dict(angle=-7200.25, is_mturn=True, velocity=300, t_acc=500, t_dec=400, power=6000),
         "cmd 15"),
        ("clamp_angle_high", dict(angle=200.0, interval=100), "single turn clamps to 180.0"),
        ("clamp_angle_low", dict(angle=-999.9, velocity=10), "single turn clamps to -180.0"),
        ("clamp_mturn_angle", dict(angle=400000.0, is_mturn=True, interval=1000),
         "multi-turn clamps to 368640.0 deg (1024 turns)"),
        ("clamp_t_acc_t_dec", dict(angle=10.0, interval=300, t_acc=5, t_dec=0),
         "t_acc and t_dec below 20 ms become 20"),
        ("clamp_velocity_low", dict(angle=10.0, velocity=0.5), "velocity below 1 dps becomes 1"),
        ("clamp_velocity_high", dict(angle=10.0, velocity=900.0), "above 750 dps becomes 750"),
        ("velocity_zero", dict(angle=10.0, velocity=0), "0 is 'given': becomes 1 dps, cmd 12"),
        ("clamp_mturn_interval_low",
         dict(angle=10.0, is_mturn=True, interval=10, t_acc=30, t_dec=40),
         "multi-turn interval below t_acc + t_dec becomes t_acc + t_dec"),
        ("clamp_mturn_interval_high", dict(angle=10.0, is_mturn=True, interval=5000000),
         "multi-turn interval above 4096000 ms becomes 4096000"),
        ("single_interval_not_clamped", dict(angle=10.0, interval=70000),
         "single-turn interval is not clamped: struct.error, nothing sent"),
        ("unknown_servo_254", dict(angle=10.0, interval=100, servo_id=254),
         "id 254 is not in the SDK's table (0-253): returns False, nothing sent"),
        ("broadcast_255", dict(angle=10.0, interval=100, servo_id=255),
         "id 255 (broadcast) is not in the SDK's table either"),
    ]
    out = []
    for name, kw, note in rows:
        args = {"servo_id": 1}
        args.update(kw)
        out.append({"name": f"set_servo_angle/{name}", "method": "set_servo_angle",
                    "args": args, "note": note, "unit": "True = request sent"})
    return out


def sync_cases():
    """Command 25 in each of its forms: send_sync_* with the per-servo records a caller packs
    (the SDK packs nothing itself), and send_sync_servo_monitor."""
    one = [(1, 900, 500, 0), (2, -900, 500, 0), (3, 0, 500, 1000)]
    out = [
        {"name": "send_sync_angle", "method": "send_sync_angle",
         "args": {"command_id": 8, "servo_num": 3, "command_data_list": sync_data("<BhHH", one)},
         "note": "records: id u8, angle i16 0.1deg, interval u16 ms, power u16 mW"},
        {"name": "send_sync_anglebyinterval", "method": "send_sync_anglebyinterval",
         "args": {"command_id": 11, "servo_num": 2, "command_data_list": sync_data(
             "<BhHHHH", [(1, 450, 1000, 100, 100, 0), (2, -450, 1000, 200, 20, 500)])},
         "note": "records: id, angle i16, interval u16, t_acc u16, t_dec u16, power u16"},
        {"name": "send_sync_anglebyvelocity", "method": "send_sync_anglebyvelocity",
         "args": {"command_id": 12, "servo_num": 2, "command_data_list": sync_data(
             "<BhHHHH", [(1, 450, 1000, 100, 100, 0), (2, -450, 2000, 20, 20, 0)])},
         "note": "records: id, angle i16, speed u16 0.1dps, t_acc, t_dec, power; sleeps 1 ms"},
        {"name": "send_sync_multiturnangle", "method": "send_sync_multiturnangle",
         "args": {"command_id": 13, "servo_num": 2, "command_data_list": sync_data(
             "<BiIH", [(1, 36000, 2000, 0), (2, -36000, 2000, 0)])},
         "note": "records: id, angle i32 0.1deg, interval u32 ms, power u16"},
        {"name": "send_sync_multiturnanglebyinterval",
         "method": "send_sync_multiturnanglebyinterval",
         "args": {"command_id": 14, "servo_num": 3, "command_data_list": sync_data(
             "<BiIHHH", [(1, 7200, 1500, 100, 100, 0), (2, -7200, 1500, 100, 100, 0),
                         (3, 123456, 4000, 300, 300, 2500)])},
         "note": "records: id, angle i32, interval u32, t_acc u16, t_dec u16, power u16"},
        {"name": "send_sync_multiturnanglebyvelocity",
         "method": "send_sync_multiturnanglebyvelocity",
         "args": {"command_id": 15, "servo_num": 2, "command_data_list": sync_data(
             "<BiHHHH", [(1, 7200, 3000, 100, 100, 0), (2, -7200, 1500, 50, 50, 1000)])},
         "note": "records: id, angle i32, speed u16 0.1dps, t_acc, t_dec, power"},
        {"name": "send_sync_multiturnanglebyinterval/17_servos_too_long",
         "method": "send_sync_multiturnanglebyinterval",
         "args": {"command_id": 14, "servo_num": 17, "command_data_list": sync_data(
             "<BiIHHH", [(i, 0, 1000, 20, 20, 0) for i in range(17)])},
         "note": "3 + 17*15 = 258 content bytes: the SDK's one-byte length cannot carry it"},
        {"name": "send_sync_servo_monitor", "method": "send_sync_servo_monitor",
         "args": {"servo_ids": [1, 2, 3]}, "unit": "{id: UartServoInfo}",
         "note": "each servo answers with its own cmd-22 reply, in the order asked"},
        {"name": "send_sync_servo_monitor/realtime", "method": "send_sync_servo_monitor",
         "args": {"servo_ids": [1, 2, 3], "realtime": True}},
        {"name": "send_sync_servo_monitor/realtime_one_missing",
         "method": "send_sync_servo_monitor", "args": {"servo_ids": [1, 2, 3], "realtime": True},
         "bus": servo_bus(1, 3),
         "note": "servo 2 is absent: after its wait the SDK marks only it unanswered"},
        {"name": "send_sync_servo_monitor/one_missing", "method": "send_sync_servo_monitor",
         "args": {"servo_ids": [1, 2, 3]}, "bus": servo_bus(1, 3),
         "note": "not realtime: the absent servo's record is returned as it was"},
        {"name": "send_sync_servo_monitor/no_data_sentinel", "method": "send_sync_servo_monitor",
         "args": {"servo_ids": [1, 2], "realtime": True},
         "bus": servo_bus(1, 2, over={2: {"monitor_no_data": True}}),
         "note": "angle -235929599 with turns 0 means 'no data': the SDK keeps nothing of it"},
    ]
    return out


def port_handler_cases():
    """The PortHandler layer (uart_pocket_handler.py), including its broken methods."""
    opts = SyncPositionControlOptions(1, 90.0, 800, 0, 100, 120)
    return [
        {"name": "PortHandler.openPort", "method": "openPort", "args": {},
         "note": "opens pyserial with these settings (timeout 0: reads never block)"},
        {"name": "PortHandler.ping", "method": "ping", "args": {"servo_id": 1}},
        {"name": "PortHandler.ping/absent", "method": "ping", "args": {"servo_id": 9}},
        {"name": "PortHandler.query_servo_monitor", "method": "query_servo_monitor",
         "args": {"servo_id": 2}},
        {"name": "PortHandler.PositionControl", "method": "PositionControl",
         "args": {"id": 1, "target_position": 0.25, "motion_time": 500}},
        {"name": "PortHandler.PositionControl_TimeBased", "method": "PositionControl_TimeBased",
         "args": {"data": opts}},
        {"name": "PortHandler.PositionControl_SpeedBased",
         "method": "PositionControl_SpeedBased",
         "args": {"id": 1, "target_position": 45.0, "motion_speed": 100, "accel_time": 50,
                  "decel_time": 50}},
        {"name": "PortHandler.PositionControl_EX", "method": "PositionControl_EX",
         "args": {"id": 1, "target_position": 45.0, "motion_time": 300},
         "note": "despite _EX, single turn: cmd 11"},
        {"name": "PortHandler.PositionControl_TimeBased_EX",
         "method": "PositionControl_TimeBased_EX",
         "args": {"id": 1, "target_position": -45.0, "motion_time": 300, "accel_time": 50,
                  "decel_time": 60, "power": 1000}},
        {"name": "PortHandler.PositionControl_SpeedBased_EX",
         "method": "PositionControl_SpeedBased_EX",
         "args": {"id": 1, "target_position": 45.0, "motion_speed": 100, "accel_time": 50,
                  "decel_time": 50}},
        {"name": "PortHandler.ReadCurrentPosition", "method": "ReadCurrentPosition",
         "args": {"id": 1}, "unit": "deg"},
        {"name": "PortHandler.ReadCurrentPosition_EX", "method": "ReadCurrentPosition_EX",
         "args": {"id": 1}, "unit": "deg (turn count dropped)"},
        {"name": "PortHandler.ResetLoop", "method": "ResetLoop", "args": {"id": 1}},
        {"name": "PortHandler.DampingControl", "method": "DampingControl",
         "args": {"id": 1, "power": 800}},
        {"name": "PortHandler.StopOnControlMode/unlocked", "method": "StopOnControlMode",
         "args": {"id": 1, "mode": "unlocked", "power": 0}},
        {"name": "PortHandler.StopOnControlMode/locked", "method": "StopOnControlMode",
         "args": {"id": 1, "mode": "locked", "power": 1000}},
        {"name": "PortHandler.StopOnControlMode/damping", "method": "StopOnControlMode",
         "args": {"id": 1, "mode": "damping", "power": 500.7}},
        {"name": "PortHandler.SyncServoMonitor", "method": "SyncServoMonitor",
         "args": {"motors": {"shoulder": 1, "elbow": 2}}},
        {"name": "PortHandler.SyncServoMonitor/realtime", "method": "SyncServoMonitor",
         "args": {"motors": {"shoulder": 1, "elbow": 2}, "realtime": True}},
        {"name": "PortHandler.SyncPositionControl_EX/ids_0_1", "method": "SyncPositionControl_EX",
         "args": {"motors": {"a": SyncPositionControlOptions(0, 900, 500, 0, 100, 100),
                             "b": SyncPositionControlOptions(1, -1800, 700, 300, 20, 40)}},
         "bus": servo_bus(0, 1),
         "note": "targets are raw 0.1deg ints here (degrees in PositionControl_TimeBased)"},
        {"name": "PortHandler.SyncPositionControl_EX/ids_1_2", "method": "SyncPositionControl_EX",
         "args": {"motors": {"a": SyncPositionControlOptions(1, 900, 500, 0, 100, 100),
                             "b": SyncPositionControlOptions(2, -900, 500, 0, 100, 100)}},
         "note": "indexes its lists by servo id: fails unless the ids are 0..n-1"},
        {"name": "PortHandler.set_origin_points", "method": "set_origin_points",
         "args": {"servo_ids": [1, 2]}},
        {"name": "PortHandler.reset_multi_turn_angles", "method": "reset_multi_turn_angles",
         "args": {"servo_ids": [1, 2]}},
        {"name": "PortHandler.read_servo_angle_monitor", "method": "read_servo_angle_monitor",
         "args": {"servo_id": 3}, "unit": "deg"},
        {"name": "PortHandler.quick_update/after_reset_user_data", "method": "quick_update",
         "args": {}, "setup": [("reset_user_data", {"servo_id": 2})],
         "note": "returns at the first whole reply instead of waiting out the 100 ms"},
        {"name": "PortHandler.clearPort", "method": "clearPort", "args": {},
         "note": "pyserial flush(): waits for output to drain; the input is kept"},
        {"name": "PortHandler.closePort", "method": "closePort", "args": {}},
        {"name": "PortHandler.read_positions", "method": "read_positions",
         "args": {"servos_id": {"shoulder": 1, "wrist": 3}}, "unit": "deg"},
    ]


def cases():
    """Every case, in output order."""
    out = [
        {"name": "ping", "method": "ping", "args": {"servo_id": 1}, "unit": "online"},
        {"name": "send_request", "method": "send_request",
         "args": {"code": 10, "param_bytes": b"\x02"},
         "note": "the raw sender every operation uses: Packet.pack(code, param_bytes), no wait"},
        {"name": "ping/absent", "method": "ping", "args": {"servo_id": 7}, "unit": "online"},
        {"name": "ping/254", "method": "ping", "args": {"servo_id": 254},
         "note": "the SDK's table holds ids 0-253"},
        {"name": "scan_servo", "method": "scan_servo", "args": {"srv_num": 4}},
        {"name": "refresh_srv_list", "method": "refresh_srv_list", "args": {"max_servo_id": 3},
         "note": "empties its table, then ping() looks the id up in it"},
        {"name": "query_servo_angle", "method": "query_servo_angle", "args": {"servo_id": 1},
         "unit": "deg"},
        {"name": "query_servo_angle/absent", "method": "query_servo_angle",
         "args": {"servo_id": 7}, "unit": "deg"},
        {"name": "query_servo_angle/absent_returns_cached", "method": "query_servo_angle",
         "args": {"servo_id": 1}, "unit": "deg",
         "setup": [("query_servo_angle", {"servo_id": 1}),
                   ("set_servo_angle", {"servo_id": 1, "angle": 10.0, "interval": 100})],
         "unplug": [1],
         "note": "servo 1 unplugged after the setup read: the old angle comes back, no error"},
        {"name": "query_servo_angle/absent_realtime", "method": "query_servo_angle",
         "args": {"servo_id": 7, "realtime": True}, "unit": "deg"},
        {"name": "query_servo_mturn_angle", "method": "query_servo_mturn_angle",
         "args": {"servo_id": 1}, "unit": "deg (turn count dropped)"},
        {"name": "query_all_srv_angle", "method": "query_all_srv_angle", "args": {},
         "note": "one cmd-10 request per id 0-253"},
        {"name": "query_srv_info", "method": "query_srv_info", "args": {"servo_id": 1},
         "note": "cmd 5 = the seed's READ_BATCH_DATA; the SDK has no handler for its reply"},
    ]
    out += set_angle_cases()
    out += [
        {"name": "set_wheel/normal_cw_default_speed", "method": "set_wheel",
         "args": {"servo_id": 1, "mode": 1}},
        {"name": "set_wheel/time_ccw", "method": "set_wheel",
         "args": {"servo_id": 1, "mode": 3, "value": 2500, "is_cw": False, "mean_dps": 45.9}},
        {"name": "set_wheel_norm", "method": "set_wheel_norm",
         "args": {"servo_id": 1, "is_cw": False, "mean_dps": 50.7}},
        {"name": "set_wheel_turn", "method": "set_wheel_turn",
         "args": {"servo_id": 1, "turn": 3, "is_cw": True, "mean_dps": 120},
         "note": "sleeps turn * 360 / mean_dps seconds (is_wait defaults to True)"},
        {"name": "set_wheel_time", "method": "set_wheel_time",
         "args": {"servo_id": 1, "interval": 1500, "is_cw": False, "is_wait": False}},
        {"name": "wheel_stop", "method": "wheel_stop", "args": {"servo_id": 1}},
        {"name": "disable_torque", "method": "disable_torque", "args": {"servo_id": 1},
         "note": "is wheel_stop: a cmd-7 stop, not cmd 24"},
        {"name": "set_damping", "method": "set_damping", "args": {"servo_id": 1, "power": 500}},
        {"name": "set_damping/default", "method": "set_damping", "args": {"servo_id": 255}},
        {"name": "reset_user_data", "method": "reset_user_data", "args": {"servo_id": 1},
         "note": "does not wait: the reply stays in the input buffer"},
        {"name": "update/after_reset_user_data", "method": "update", "args": {},
         "setup": [("reset_user_data", {"servo_id": 1})],
         "note": "the next update() consumes the leftover reply"},
        {"name": "read_data/baudrate", "method": "read_data",
         "args": {"servo_id": 1, "address": 36}, "unit": "raw bytes"},
        {"name": "read_data/serial_number", "method": "read_data",
         "args": {"servo_id": 2, "address": 8}, "unit": "raw bytes"},
        {"name": "read_data/angle_limit_low", "method": "read_data",
         "args": {"servo_id": 1, "address": 52}, "unit": "raw bytes"},
        {"name": "read_data/absent", "method": "read_data",
         "args": {"servo_id": 7, "address": 36}},
        {"name": "read_data/absent_realtime", "method": "read_data",
         "args": {"servo_id": 7, "address": 36, "realtime": True}},
        {"name": "write_data/response_switch", "method": "write_data",
         "args": {"servo_id": 1, "address": 33, "content": b"\x01"}, "unit": "written"},
        {"name": "write_data/angle_limit_high", "method": "write_data",
         "args": {"servo_id": 1, "address": 51, "content": struct.pack("<h", 1350)},
         "unit": "written"},
        {"name": "write_data/refused", "method": "write_data",
         "args": {"servo_id": 1, "address": 36, "content": b"\x07"},
         "bus": servo_bus(1, over={1: {"write_result": 0}}), "unit": "written"},
        {"name": "write_data/servo_id_reply_from_new_id", "method": "write_data",
         "args": {"servo_id": 1, "address": 34, "content": b"\x05"}, "unit": "written",
         "note": "the reply comes from id 5: the SDK files it under 5 and returns False"},
        {"name": "write_data/absent_realtime", "method": "write_data",
         "args": {"servo_id": 7, "address": 33, "content": b"\x00", "realtime": True}},
        {"name": "query_voltage", "method": "query_voltage", "args": {"servo_id": 1},
         "unit": "V"},
        {"name": "query_current", "method": "query_current", "args": {"servo_id": 1},
         "unit": "A"},
        {"name": "query_power", "method": "query_power", "args": {"servo_id": 1}, "unit": "W"},
        {"name": "query_status", "method": "query_status", "args": {"servo_id": 1},
         "unit": "raw status byte"},
        {"name": "query_voltage/absent_realtime", "method": "query_voltage",
         "args": {"servo_id": 7, "realtime": True}, "unit": "V"},
    ]
    out += temperature_cases()
    out += [
        {"name": "query_servo_monitor", "method": "query_servo_monitor",
         "args": {"servo_id": 1}},
        {"name": "query_servo_monitor/no_data_sentinel", "method": "query_servo_monitor",
         "args": {"servo_id": 1}, "bus": servo_bus(1, over={1: {"monitor_no_data": True}})},
        {"name": "query_servo_monitor/absent_realtime", "method": "query_servo_monitor",
         "args": {"servo_id": 7, "realtime": True}},
        {"name": "set_origin_point", "method": "set_origin_point", "args": {"servo_id": 1}},
        {"name": "reset_multi_turn_angle", "method": "reset_multi_turn_angle",
         "args": {"servo_id": 1}},
        {"name": "stop_on_control_mode/release", "method": "stop_on_control_mode",
         "args": {"servo_id": 1, "method": 0x10, "power": 0}},
        {"name": "stop_on_control_mode/hold", "method": "stop_on_control_mode",
         "args": {"servo_id": 1, "method": 0x11, "power": 1000}},
        {"name": "stop_on_control_mode/damping", "method": "stop_on_control_mode",
         "args": {"servo_id": 2, "method": 0x12, "power": 500}},
        {"name": "begin_async", "method": "begin_async", "args": {},
         "note": "no servo id: every servo on the bus buffers the commands that follow"},
        {"name": "end_async/execute", "method": "end_async", "args": {"cancel": 0}},
        {"name": "end_async/cancel", "method": "end_async", "args": {"cancel": 1}},
    ]
    out += sync_cases()
    for c in port_handler_cases():
        c["api"] = "PortHandler"
        out.append(c)
    out += [
        {"name": "quirk/one_wire_echo_ping", "method": "ping", "args": {"servo_id": 1},
         "echo": True, "note": "a one-wire bus echoes the request; the SDK skips 12 4C"},
        {"name": "quirk/one_wire_echo_holding_051c", "method": "write_data",
         "args": {"servo_id": 1, "address": 39, "content": struct.pack("<H", 7173)},
         "echo": True, "unit": "written",
         "note": "the echoed request holds 05 1C (7173 = 0x1C05): the SDK takes it for a reply "
                 "header, swallows the real reply, returns False"},
        {"name": "quirk/split_reply_update", "method": "query_servo_angle",
         "args": {"servo_id": 1}, "split_at": 3, "unit": "deg",
         "note": "reply in two bursts 16 ms apart (FTDI latency timer): update() copes"},
        {"name": "quirk/split_reply_quick_update", "method": "ping", "args": {"servo_id": 1},
         "api": "PortHandler", "split_at": 3,
         "note": "PortHandler.ping uses quick_update(), which feeds its whole buffer again on "
                 "each burst: the split reply is lost"},
    ]
    return out


def main():
    clock = FakeClock()
    uservo.time = clock
    uart_pocket_handler.time = clock
    meta = {"kind": "meta"}
    meta.update(sdk_versions())
    meta.update({
        "generator": "tests/sdk/sdk_vectors.py",
        "fake_bus": "servos 1,2,3 unless a line says otherwise: angle -45.6 deg (i16 -456), "
                    "multi-turn angle 1234.5 deg (i32 12345) in turn 3, 7400 mV, 120 mA, 888 mW,"
                    " thermistor raw 2048 (25 degC), status 0x01; replies 0.5 ms after a request",
        "units": INFO_UNITS,
    })
    emit(meta)
    names = set()
    for case in cases():
        if case["name"] in names:
            raise SystemExit(f"duplicate case name {case['name']}")
        names.add(case["name"])
        emit(run_case(case, clock))


if __name__ == "__main__":
    main()
