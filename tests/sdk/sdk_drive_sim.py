#!/usr/bin/env python3
"""Drives a real serial port with the servo vendor's Python SDK and checks the answers.

    /work/sdk-venv/bin/python tests/sdk/sdk_drive_sim.py PORT [--ids 1,2,3] [--baud 115200]

Meant for `botbench sim servo-bus --servos 1,2,3` (it prints the pty path on its first line), or a
real bus whose servos have those ids. Calls every operation of the SDK's servo API (commands 1-25,
both UartServoManager and PortHandler) and prints one JSON document a line: the operation, the
bytes the SDK wrote and received, what it returned, and a check of the outcome where one can be
made (a motion command is checked by reading the angle back until it arrives or a deadline
passes). The last line is a summary; the exit code is 1 when any check failed.

It moves the servos and, as its last step, resets servo ids[0]'s user data (then writes its id
back): run it on a simulator or a bench rig, never on a machine.
"""

import argparse
import os
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from sdk_common import (  # noqa: E402
    REPLY_HEADER,
    Captured,
    split_frames,
    call,
    emit,
    frames_json,
    jsonable,
    open_port_handler,
    sdk_versions,
    writes_json,
)

import serial  # noqa: E402
from fashionstar_uart_sdk.uart_pocket_handler import SyncPositionControlOptions  # noqa: E402
from fashionstar_uart_sdk.uservo import UartServoManager  # noqa: E402

# How close (degrees) a read-back angle must come to a target.
ANGLE_TOLERANCE = 0.5
# Beyond a motion's own duration, how long to keep reading the angle before calling it failed.
SETTLE_S = 3.0
# An id nobody on the bus has.
ABSENT_ID = 200
# PortHandler.ping and .query_servo_monitor read through quick_update(), which feeds its whole
# buffer to the frame parser again each time more bytes arrive: a reply that arrives in two pieces
# split after its header is lost (an SDK defect; USB adapters and the simulator deliver in pieces).
# Such a step passes when the reply itself arrived whole (the simulator is then not at fault).
# The SDK waits exactly 100 ms for a reply; on a loaded host (PROTOCOL_NOTES section 4) a reply
# can come later and is lost. Reads are therefore tried up to READ_ATTEMPTS times, motion commands
# once (their checks read the angle back several times).
READ_ATTEMPTS = 3
READS = {
    "ping", "scan_servo", "query_servo_angle", "query_servo_mturn_angle", "read_data",
    "write_data", "query_voltage", "query_current", "query_power", "query_temperature",
    "query_status", "query_servo_monitor", "send_sync_servo_monitor", "SyncServoMonitor",
    "read_positions", "ReadCurrentPosition", "ReadCurrentPosition_EX", "read_servo_angle_monitor",
}  # fmt: skip


# How long in_waiting sleeps when nothing has come.
IDLE_POLL_S = 0.0005


class RecordingSerial:
    """serial.Serial that keeps what went each way since the last take()."""

    def __init__(self, **kw):
        self.port = serial.Serial(**kw)
        self.tx, self.rx = [], bytearray()

    def write(self, data):
        self.tx.append(bytes(data))
        return self.port.write(data)

    @property
    def in_waiting(self):
        # The SDK polls this in a busy loop for its whole 100 ms reply wait: a short sleep when
        # nothing has come keeps that loop from taking a core from the tests beside it (the wait
        # still ends by the SDK's own clock, and an answer is seen within IDLE_POLL_S).
        n = self.port.in_waiting
        if not n:
            time.sleep(IDLE_POLL_S)
        return n

    @property
    def is_open(self):
        return self.port.is_open

    def read(self, size=1):
        data = self.port.read(size)
        self.rx += data
        return data

    def flush(self):
        self.port.flush()

    def close(self):
        self.port.close()

    def take(self):
        tx, rx = self.tx, bytes(self.rx)
        self.tx, self.rx = [], bytearray()
        return tx, rx


class Driver:
    """Runs steps against one SDK object and prints each."""

    def __init__(self, sdk, port, api):
        self.sdk, self.port, self.api = sdk, port, api
        self.results = []

    def step(self, name, method, args, check=None, quick_update=None, sdk_defect=None):
        """Calls sdk.method(**args); `check(value)` then says (ok, observed, what was checked).

        quick_update=(cmd, servo id): the SDK reads through quick_update() (see QUICK_UPDATE);
        when it lost the reply, the step still passes if that reply arrived whole.
        sdk_defect: why the SDK itself cannot do this step; it is then not checked."""
        if self.api == "PortHandler":
            name = f"PortHandler.{name}"
        if sdk_defect:
            check = None
        attempts = READ_ATTEMPTS if method in READS else 1
        for attempt in range(1, attempts + 1):
            self.port.take()
            with Captured() as cap:
                value, error = call(lambda: getattr(self.sdk, method)(**args))
            tx, rx = self.port.take()
            ok, observed, what = None, None, None
            if check is not None and error is None:
                ok, observed, what = check(value)
            elif check is not None:
                ok, what = False, "the call raised"
            verify_tx, _ = self.port.take()
            lost = False
            if ok is False and quick_update:
                arrived = [c for c, body, _ in split_frames(rx, REPLY_HEADER)
                           if c == quick_update[0] and body[:1] == bytes([quick_update[1]])]
                lost = ok = bool(arrived)
            if ok is not False:
                break
        doc = {
            "kind": "step",
            "name": name,
            "api": self.api,
            "method": method,
            "args": {k: (v.hex() if isinstance(v, bytes) else jsonable(v)) for k, v in args.items()},
            "requests": writes_json(tx),
            "received": {"hex": rx.hex(), "frames": frames_json(rx, REPLY_HEADER)},
            "returned": jsonable(value),
            "error": error,
            "ok": ok,
        }
        if what:
            doc["check"] = what
        if observed is not None:
            doc["observed"] = jsonable(observed)
        if verify_tx:
            doc["check_requests"] = len(verify_tx)
        if attempt > 1:
            doc["attempts"] = attempt
        if lost:
            doc["sdk_lost_reply"] = "the reply arrived whole (see received); quick_update lost it"
        if sdk_defect:
            doc["sdk_defect"] = sdk_defect
        if cap.logs:
            doc["log"] = cap.logs
        emit(doc)
        self.results.append((name, ok))
        return value


def read_angle(sdk, sid, mturn, tries=3):
    """Servo sid's angle (cmd 16 if mturn, else cmd 10), asked up to `tries` times: the SDK
    gives a reply 100 ms, which a loaded host can miss. None if it never came."""
    read = sdk.query_servo_mturn_angle if mturn else sdk.query_servo_angle
    for _ in range(tries):
        a = read(sid, realtime=True)
        if a is not None:
            return a
    return None


def wait_angle(sdk, sid, target, mturn, within_s):
    """Reads servo sid's angle (cmd 16 if mturn, else 10) until it is within ANGLE_TOLERANCE of
    target or within_s + SETTLE_S has passed. Returns the last angle read (None if none)."""
    deadline = time.monotonic() + within_s + SETTLE_S
    last = None
    while True:
        a = read_angle(sdk, sid, mturn, tries=1)
        last = a if a is not None else last
        if a is not None and abs(a - target) <= ANGLE_TOLERANCE:
            return a
        if time.monotonic() > deadline:
            return last


def arrives(sdk, sid, target, mturn=False, within_s=0.0):
    """A check: servo sid reaches target (degrees)."""
    def check(_value):
        a = wait_angle(sdk, sid, target, mturn, within_s)
        ok = a is not None and abs(a - target) <= ANGLE_TOLERANCE
        return ok, a, f"servo {sid} reads back {target} deg ({'cmd 16' if mturn else 'cmd 10'})"
    return check


def all_arrive(sdk, targets, mturn, within_s):
    """A check: every servo reaches its target ({id: degrees})."""
    def check(_value):
        got = {sid: wait_angle(sdk, sid, t, mturn, within_s) for sid, t in targets.items()}
        ok = all(a is not None and abs(a - targets[s]) <= ANGLE_TOLERANCE for s, a in got.items())
        return ok, got, f"each servo reads back its target {targets}"
    return check


def stays(sdk, sid, mturn=True, gap_s=0.3):
    """A check: servo sid comes to rest: two reads gap_s apart agree, within SETTLE_S (a timed
    spin the SDK waited for can outlast its wait by the host's lateness). Returns (ok, (a, b),
    what)."""
    def check(_value):
        deadline = time.monotonic() + SETTLE_S
        while True:
            a = read_angle(sdk, sid, mturn)
            time.sleep(gap_s)
            b = read_angle(sdk, sid, mturn)
            ok = a is not None and b is not None and abs(a - b) <= ANGLE_TOLERANCE
            if ok or time.monotonic() > deadline:
                return ok, [a, b], f"servo {sid} holds still over {gap_s} s"
    return check


def still_at(sdk, sid, angle, gap_s=0.3):
    """A check: after gap_s, servo sid still reads angle (single-turn read, cmd 10)."""
    def check(_value):
        time.sleep(gap_s)
        a = read_angle(sdk, sid, False)
        ok = a is not None and abs(a - angle) <= ANGLE_TOLERANCE
        return ok, a, f"servo {sid} still at {angle} deg after {gap_s} s"
    return check


def wrapped(deg):
    """A multi-turn angle brought into one turn, (-180, 180]."""
    a = deg % 360.0
    return a - 360.0 if a > 180.0 else a


def moves(sdk, sid, gap_s=0.3):
    """A check: servo sid's multi-turn angle changes over gap_s."""
    def check(_value):
        a = read_angle(sdk, sid, True)
        time.sleep(gap_s)
        b = read_angle(sdk, sid, True)
        ok = a is not None and b is not None and abs(a - b) > ANGLE_TOLERANCE
        return ok, [a, b], f"servo {sid} turns (angle changes over {gap_s} s)"
    return check


def equals(expected, what):
    return lambda v: (v == expected, None, what)


def plausible_temp(v):
    ok = v is not None and -20.0 <= v <= 100.0
    return ok, None, "a plausible temperature, -20..100 degC (SDK conversion)"


def monitor_ok(sdk, sid):
    """A check of a MONITOR result: values present, and its temperature (SDK conversion of the
    raw reading) agrees with parameter 4's (same conversion) within 2 degC."""
    def check(info):
        if info is None or info.voltage is None:
            return False, None, "MONITOR values decoded"
        t22 = info.temp  # the SDK keeps one record per servo: read it before parameter 4 does
        t4 = sdk.query_temperature(sid, realtime=True) if t22 is not None else None
        ok = t4 is not None and abs(t4 - t22) <= 2.0 and plausible_temp(t22)[0]
        return ok, {"monitor_temp": t22, "param4_temp": t4}, (
            "MONITOR decoded; its temperature is plausible and agrees with parameter 4's")
    return check


def sync_monitor_ok(ids):
    def check(result):
        missing = [s for s in ids if result.get(s) is None or result[s].voltage is None]
        return not missing, {"missing": missing}, f"every servo of {ids} answers in one exchange"
    return check


def manager_steps(d, sdk, ids):
    """Every UartServoManager operation."""
    sid, others = ids[0], ids[1:]
    for s in ids:
        d.step(f"ping/{s}", "ping", {"servo_id": s}, equals(True, "online"))
    d.step("ping/absent", "ping", {"servo_id": ABSENT_ID}, equals(False, "absent: no answer"))
    d.step("scan_servo", "scan_servo", {"srv_num": 5},
           lambda _v: (all(sdk.servos[s].is_online == (s in ids) for s in range(5)),
                       [s for s in range(5) if sdk.servos[s].is_online], "online ids 0-4"))
    d.step("query_servo_angle", "query_servo_angle", {"servo_id": sid, "realtime": True},
           lambda v: (isinstance(v, float), None, "an angle"))
    d.step("query_servo_mturn_angle", "query_servo_mturn_angle",
           {"servo_id": sid, "realtime": True}, lambda v: (isinstance(v, float), None, "an angle"))
    d.step("read_data/servo_id", "read_data", {"servo_id": sid, "address": 34, "realtime": True},
           equals(bytes([sid]), "parameter 34 is the servo's id"))
    d.step("read_data/baudrate", "read_data", {"servo_id": sid, "address": 36, "realtime": True},
           equals(b"\x05", "parameter 36 is option 5 (115200)"))
    d.step("write_data/response_switch", "write_data",
           {"servo_id": sid, "address": 33, "content": b"\x00", "realtime": True},
           equals(True, "written"))
    for q, unit in (("voltage", "V"), ("current", "A"), ("power", "W")):
        d.step(f"query_{q}", f"query_{q}", {"servo_id": sid, "realtime": True},
               lambda v, unit=unit: (isinstance(v, float), None, f"a value in {unit}"))
    d.step("query_temperature", "query_temperature", {"servo_id": sid, "realtime": True},
           plausible_temp)
    d.step("query_status", "query_status", {"servo_id": sid, "realtime": True},
           lambda v: (isinstance(v, int), None, "a status byte"))
    d.step("query_servo_monitor", "query_servo_monitor", {"servo_id": sid, "realtime": True},
           monitor_ok(sdk, sid))
    d.step("query_srv_info", "query_srv_info", {"servo_id": sid},
           lambda _v: (None, None, "cmd 5; the SDK has no handler for the reply"))

    # Angle commands of every kind.
    d.step("set_servo_angle/cmd8_interval_zero", "set_servo_angle",
           {"servo_id": sid, "angle": 45.0, "interval": 0}, arrives(sdk, sid, 45.0))
    d.step("set_servo_angle/cmd10_cmd8_mean_dps", "set_servo_angle",
           {"servo_id": sid, "angle": 0.0, "mean_dps": 200.0}, arrives(sdk, sid, 0.0, within_s=1))
    d.step("set_servo_angle/cmd11_by_interval", "set_servo_angle",
           {"servo_id": sid, "angle": 90.0, "interval": 300, "t_acc": 50, "t_dec": 50},
           arrives(sdk, sid, 90.0, within_s=0.3))
    d.step("set_servo_angle/cmd12_by_velocity", "set_servo_angle",
           {"servo_id": sid, "angle": -60.0, "velocity": 300.0, "t_acc": 50, "t_dec": 50},
           arrives(sdk, sid, -60.0, within_s=0.5))
    d.step("set_servo_angle/cmd13_mturn", "set_servo_angle",
           {"servo_id": sid, "angle": 720.0, "is_mturn": True, "interval": 0},
           arrives(sdk, sid, 720.0, mturn=True))
    d.step("set_servo_angle/cmd14_mturn_by_interval", "set_servo_angle",
           {"servo_id": sid, "angle": -1080.5, "is_mturn": True, "interval": 500, "t_acc": 100,
            "t_dec": 100, "power": 0}, arrives(sdk, sid, -1080.5, mturn=True, within_s=0.5))
    d.step("set_servo_angle/cmd15_mturn_by_velocity", "set_servo_angle",
           {"servo_id": sid, "angle": 400.0, "is_mturn": True, "velocity": 750.0, "t_acc": 20,
            "t_dec": 20}, arrives(sdk, sid, 400.0, mturn=True, within_s=2.0))
    before = read_angle(sdk, sid, True) or 0.0
    d.step("reset_multi_turn_angle", "reset_multi_turn_angle", {"servo_id": sid},
           arrives(sdk, sid, wrapped(before), mturn=True))
    d.step("set_origin_point", "set_origin_point", {"servo_id": sid},
           arrives(sdk, sid, 0.0, mturn=True))
    d.step("set_servo_angle/cmd10_cmd13_long_move", "set_servo_angle",
           {"servo_id": sid, "angle": 3600.0, "is_mturn": True, "mean_dps": 100.0},
           moves(sdk, sid))
    d.step("stop_on_control_mode/hold", "stop_on_control_mode",
           {"servo_id": sid, "method": 0x11, "power": 500}, stays(sdk, sid))
    d.step("stop_on_control_mode/release", "stop_on_control_mode",
           {"servo_id": sid, "method": 0x10, "power": 0}, None)
    d.step("stop_on_control_mode/damping", "stop_on_control_mode",
           {"servo_id": sid, "method": 0x12, "power": 500}, None)

    # Wheel mode and damping (cmd 7, 9).
    d.step("set_wheel_norm", "set_wheel_norm", {"servo_id": sid, "is_cw": True, "mean_dps": 90},
           moves(sdk, sid))
    d.step("wheel_stop", "wheel_stop", {"servo_id": sid}, stays(sdk, sid))
    before = read_angle(sdk, sid, True) or 0.0
    d.step("set_wheel_turn", "set_wheel_turn",
           {"servo_id": sid, "turn": 1, "is_cw": True, "mean_dps": 360, "is_wait": True},
           arrives(sdk, sid, before + 360.0, mturn=True))
    d.step("set_wheel_time", "set_wheel_time",
           {"servo_id": sid, "interval": 300, "is_cw": False, "mean_dps": 100, "is_wait": True},
           stays(sdk, sid))
    d.step("set_wheel/normal_ccw", "set_wheel", {"servo_id": sid, "mode": 1, "is_cw": False},
           moves(sdk, sid))
    d.step("disable_torque", "disable_torque", {"servo_id": sid}, stays(sdk, sid))
    d.step("set_damping", "set_damping", {"servo_id": sid, "power": 500}, None)

    # Asynchronous motion (cmd 18/19): commands are held until end_async(0), dropped on 1.
    d.step("set_servo_angle/start_at_0", "set_servo_angle",
           {"servo_id": sid, "angle": 0.0, "interval": 0}, arrives(sdk, sid, 0.0))
    d.step("begin_async", "begin_async", {}, None)
    d.step("set_servo_angle/held_by_async", "set_servo_angle",
           {"servo_id": sid, "angle": 30.0, "interval": 0}, still_at(sdk, sid, 0.0))
    d.step("end_async/execute", "end_async", {"cancel": 0}, arrives(sdk, sid, 30.0))
    d.step("begin_async/again", "begin_async", {}, None)
    d.step("set_servo_angle/to_be_cancelled", "set_servo_angle",
           {"servo_id": sid, "angle": -30.0, "interval": 0}, None)
    d.step("end_async/cancel", "end_async", {"cancel": 1}, still_at(sdk, sid, 30.0))

    # Synchronous commands (cmd 25) in each form.
    n = len(ids)
    single = {s: 10.0 * (i + 1) for i, s in enumerate(ids)}
    mturn = {s: 400.0 * (i + 1) for i, s in enumerate(ids)}

    # (method, sub-command, record layout, target deg per servo, multi-turn, motion s, record)
    forms = [
        ("send_sync_angle", 8, "<BhHH", single, False, 0,
         lambda s, t: (s, int(t * 10), 0, 0)),
        ("send_sync_anglebyinterval", 11, "<BhHHHH", {s: -a for s, a in single.items()}, False,
         0.3, lambda s, t: (s, int(t * 10), 300, 50, 50, 0)),
        ("send_sync_anglebyvelocity", 12, "<BhHHHH", {s: 2 * a for s, a in single.items()},
         False, 0.5, lambda s, t: (s, int(t * 10), 3000, 20, 20, 0)),
        ("send_sync_multiturnangle", 13, "<BiIH", mturn, True, 0,
         lambda s, t: (s, int(t * 10), 0, 0)),
        ("send_sync_multiturnanglebyinterval", 14, "<BiIHHH",
         {s: -a for s, a in mturn.items()}, True, 0.5,
         lambda s, t: (s, int(t * 10), 500, 100, 100, 0)),
        ("send_sync_multiturnanglebyvelocity", 15, "<BiHHHH",
         {s: a / 2 for s, a in mturn.items()}, True, 2.0,
         lambda s, t: (s, int(t * 10), 7500, 20, 20, 0)),
    ]
    for method, sub, fmt, targets, is_mturn, within_s, record in forms:
        data = [struct.pack(fmt, *record(s, targets[s])) for s in ids]
        d.step(method, method, {"command_id": sub, "servo_num": n, "command_data_list": data},
               all_arrive(sdk, targets, is_mturn, within_s))
    d.step("send_sync_servo_monitor", "send_sync_servo_monitor",
           {"servo_ids": ids, "realtime": True}, sync_monitor_ok(ids))
    if others:
        d.step("send_sync_servo_monitor/with_absent", "send_sync_servo_monitor",
               {"servo_ids": [ABSENT_ID] + ids, "realtime": True}, sync_monitor_ok(ids))


def reset_steps(d, sdk, ids):
    """RESET_USER_DATA last: it restores the factory id (0), so the id is written back."""
    sid = ids[0]
    d.step("reset_user_data", "reset_user_data", {"servo_id": sid}, None)
    d.step("update/consumes_reset_reply", "update", {"wait_response": True},
           lambda v: (v is True, None, "the reset's reply (cmd 2) arrives"))
    d.step("write_data/restore_id", "write_data",
           {"servo_id": 0, "address": 34, "content": bytes([sid]), "realtime": True}, None)
    d.step("ping/after_restore", "ping", {"servo_id": sid}, equals(True, "back on its id"))


def port_handler_steps(d, ph, ids):
    """Every PortHandler operation (uart_pocket_handler.py)."""
    sid = ids[0]
    motors = {f"servo{s}": s for s in ids}
    d.step("ping", "ping", {"servo_id": sid}, equals(True, "online"), quick_update=(1, sid))
    d.step("query_servo_monitor", "query_servo_monitor", {"servo_id": sid, "realtime": True},
           lambda v: (v is not None and v.voltage is not None, None, "MONITOR values decoded"),
           quick_update=(22, sid))
    d.step("PositionControl", "PositionControl",
           {"id": sid, "target_position": 0.1, "motion_time": 300}, None,
           sdk_defect="reads self.min_position_limit, which nothing sets: AttributeError")
    d.step("PositionControl_EX", "PositionControl_EX",
           {"id": sid, "target_position": 45.0, "motion_time": 300},
           arrives(ph, sid, 45.0, within_s=0.3))
    d.step("PositionControl_TimeBased", "PositionControl_TimeBased",
           {"data": SyncPositionControlOptions(sid, -45.0, 300, 0, 50, 50)},
           arrives(ph, sid, -45.0, within_s=0.3))
    d.step("PositionControl_TimeBased_EX", "PositionControl_TimeBased_EX",
           {"id": sid, "target_position": 60.0, "motion_time": 300, "accel_time": 50,
            "decel_time": 50}, arrives(ph, sid, 60.0, within_s=0.3))
    d.step("PositionControl_SpeedBased", "PositionControl_SpeedBased",
           {"id": sid, "target_position": 0.0, "motion_speed": 100, "accel_time": 50,
            "decel_time": 50}, None,
           sdk_defect="passes voltage= to set_servo_angle(): TypeError")
    d.step("PositionControl_SpeedBased_EX", "PositionControl_SpeedBased_EX",
           {"id": sid, "target_position": 0.0, "motion_speed": 100, "accel_time": 50,
            "decel_time": 50}, None,
           sdk_defect="passes voltage= to set_servo_angle(): TypeError")
    d.step("ReadCurrentPosition", "ReadCurrentPosition", {"id": sid},
           lambda v: (v is not None and abs(v - 60.0) <= ANGLE_TOLERANCE, None, "60 deg"))
    d.step("ReadCurrentPosition_EX", "ReadCurrentPosition_EX", {"id": sid},
           lambda v: (isinstance(v, float), None, "an angle"))
    d.step("ResetLoop", "ResetLoop", {"id": sid}, None)
    d.step("DampingControl", "DampingControl", {"id": sid, "power": 500}, None)
    d.step("StopOnControlMode", "StopOnControlMode", {"id": sid, "mode": "locked", "power": 500},
           stays(ph, sid))
    d.step("SyncServoMonitor", "SyncServoMonitor", {"motors": motors, "realtime": True},
           lambda v: (all(m.voltage is not None for m in v.values()), None,
                      "every servo's monitor values"))
    targets = {f"servo{s}": SyncPositionControlOptions(s, 900 * (i + 1), 300, 0, 50, 50)
               for i, s in enumerate(ids)}
    d.step("SyncPositionControl_EX", "SyncPositionControl_EX", {"motors": targets},
           all_arrive(ph, {s: 90.0 * (i + 1) for i, s in enumerate(ids)}, True, 0.3),
           sdk_defect=None if ids == list(range(len(ids))) else
           "indexes its lists by servo id: raises IndexError unless the ids are 0..n-1")
    d.step("set_origin_points", "set_origin_points", {"servo_ids": ids},
           all_arrive(ph, {s: 0.0 for s in ids}, True, 0))
    d.step("reset_multi_turn_angles", "reset_multi_turn_angles", {"servo_ids": ids}, None)
    d.step("read_servo_angle_monitor", "read_servo_angle_monitor", {"servo_id": sid},
           lambda v: (v is not None and abs(v) <= ANGLE_TOLERANCE, None, "0 deg after origin"),
           quick_update=(22, sid))
    d.step("read_positions", "read_positions", {"servos_id": motors},
           lambda v: (all(p is not None for p in v.values()), None, "a position for each"))
    d.step("clearPort", "clearPort", {}, None)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("port")
    ap.add_argument("--ids", default="1,2,3", help="the servo ids on the bus (default 1,2,3)")
    ap.add_argument("--baud", type=int, default=115200)
    a = ap.parse_args()
    ids = [int(x) for x in a.ids.split(",") if x]
    meta = {"kind": "meta"}
    meta.update(sdk_versions())
    meta.update({"generator": "tests/sdk/sdk_drive_sim.py", "port": a.port, "ids": ids,
                 "baud": a.baud})
    emit(meta)

    port = RecordingSerial(port=a.port, baudrate=a.baud, parity=serial.PARITY_NONE,
                           stopbits=1, bytesize=8, timeout=0)
    d = Driver(UartServoManager(port), port, "UartServoManager")
    manager_steps(d, d.sdk, ids)
    results = d.results
    port.close()

    holder = {}

    def make(**kw):
        holder["port"] = RecordingSerial(**kw)
        return holder["port"]

    ph, _ = open_port_handler(make, a.port, a.baud)
    d = Driver(ph, holder["port"], "PortHandler")
    port_handler_steps(d, ph, ids)
    d.sdk = UartServoManager(holder["port"])
    d.api = "UartServoManager"
    reset_steps(d, d.sdk, ids)
    results += d.results
    holder["port"].close()

    failed = [n for n, ok in results if ok is False]
    emit({"kind": "summary", "steps": len(results),
          "ok": sum(1 for _, ok in results if ok), "failed": failed,
          "unchecked": [n for n, ok in results if ok is None]})
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
