//! Generated records of a plausible line, for the report's benchmark (a million step records),
//! the screenshot tour's Yield view and tests: window cleaners self-tested at two stations of
//! four slots, ten measured steps each, about 4 % failing a step and retested once, and one
//! measurement (the fan current) drifting toward its high limit over the last units.

use super::record::{
    Measurement, Record, RunContext, RunKind, SerialSource, StepRecord, Unit, Verdict,
};

/// A generated step: name, measurement, unit, low, high, mean, sigma.
type StepSpec = (
    &'static str,
    &'static str,
    &'static str,
    Option<f64>,
    Option<f64>,
    f64,
    f64,
);

/// The generated steps' names in 中文 (the records keep the English; the Yield view shows these).
pub const STEP_NAMES_ZH: [(&str, &str); 10] = [
    ("Battery voltage", "电池电压"),
    ("Adapter voltage", "适配器电压"),
    ("Gyro at rest", "静止时陀螺仪"),
    ("Accelerometer at rest", "静止时加速度计"),
    ("Wheels forward", "轮子正转"),
    ("Wheels backward", "轮子反转"),
    ("Fan current", "风机电流"),
    ("Spray pump", "喷水泵"),
    ("Pressure sensor", "压力传感器"),
    ("Water box", "水箱"),
];

/// The steps every generated unit runs.
const STEPS: [StepSpec; 10] = [
    (
        "Battery voltage",
        "batteryVoltage",
        "V",
        Some(11.5),
        Some(12.6),
        12.05,
        0.12,
    ),
    (
        "Adapter voltage",
        "adapterVoltage",
        "V",
        Some(23.0),
        Some(25.0),
        24.0,
        0.25,
    ),
    (
        "Gyro at rest",
        "gyroX spread",
        "°/s",
        None,
        Some(30.0),
        9.0,
        4.0,
    ),
    (
        "Accelerometer at rest",
        "accZ",
        "g",
        Some(0.9),
        Some(1.1),
        1.0,
        0.02,
    ),
    (
        "Wheels forward",
        "adcLeftWheel rise",
        "",
        Some(200.0),
        None,
        420.0,
        60.0,
    ),
    (
        "Wheels backward",
        "adcRightWheel rise",
        "",
        Some(200.0),
        None,
        415.0,
        60.0,
    ),
    (
        "Fan current",
        "fanCurrent",
        "A",
        Some(0.8),
        Some(1.6),
        1.15,
        0.07,
    ),
    (
        "Spray pump",
        "pumpCurrent",
        "A",
        Some(0.1),
        Some(0.5),
        0.28,
        0.04,
    ),
    (
        "Pressure sensor",
        "pressure",
        "kPa",
        Some(95.0),
        Some(105.0),
        100.0,
        1.2,
    ),
    ("Water box", "waterBox", "", Some(0.5), Some(1.5), 1.0, 0.0),
];

/// The plan name and hash the generated records carry.
pub const PLAN: &str = "Window cleaner line test";
/// See [`PLAN`].
pub const PLAN_SHA256: &str = "5e1f7a0c3b9d2e8f4a6b1c0d9e8f7a6b5c4d3e2f1a0b9c8d7e6f5a4b3c2d1e0f";

/// A small deterministic generator (xorshift; no dependency on the seed's platform).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Normal(0, 1), by Box-Muller.
    fn normal(&mut self) -> f64 {
        let u = self.unit().max(1e-12);
        let v = self.unit();
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// `units` units spread evenly from `start_ms` to `end_ms`, each one record (a failed unit two:
/// its retest follows a minute later), handed to `each` in time order. Deterministic for a
/// `seed`. Each record has [`STEPS`]`.len()` steps of one measurement each.
pub fn generate(units: usize, start_ms: i64, end_ms: i64, seed: u64, each: &mut dyn FnMut(Record)) {
    let mut rng = Rng(seed.max(1).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let span = (end_ms - start_ms).max(1) as f64;
    let drift_from = units.saturating_sub(300);
    for u in 0..units {
        let t = start_ms + (span * u as f64 / units.max(1) as f64) as i64;
        let station = if u % 2 == 0 { "line1-st1" } else { "line1-st2" };
        let slot = ((u / 2) % 4 + 1).to_string();
        let serial = format!("WC{:07}", u + 1);
        // The fan current walks up over the last 300 units: 0.3 of its limit gap.
        let drift = if u >= drift_from {
            0.25 * (u - drift_from) as f64 / 300.0
        } else {
            0.0
        };
        let first = unit_run(&mut rng, t, station, &slot, &serial, drift, 0.04);
        let failed = first.verdict == Verdict::Fail;
        each(first);
        if failed {
            each(unit_run(
                &mut rng,
                t + 60_000,
                station,
                &slot,
                &serial,
                drift,
                0.3,
            ));
        }
    }
}

/// One run of a unit: each step's value drawn from its normal, and with `p_fail` one step
/// pushed past a limit.
fn unit_run(
    rng: &mut Rng,
    t: i64,
    station: &str,
    slot: &str,
    serial: &str,
    fan_drift: f64,
    p_fail: f64,
) -> Record {
    let mut r = Record::start(
        RunKind::Selftest,
        PLAN,
        Some(PLAN_SHA256.into()),
        "window-cleaner",
    );
    r.uuid = format!("{:016x}-{:016x}", rng.next(), rng.next());
    r.started_ms = t;
    r.utc_offset_min = 0;
    r.host = "demo-pc".into();
    r.context = RunContext {
        station: Some(station.into()),
        slot: Some(slot.into()),
        fixture: Some(format!("fixture {slot}")),
        operator: Some(
            if (t / 28_800_000) % 2 == 0 {
                "li.wei"
            } else {
                "zhang.min"
            }
            .into(),
        ),
        bundle_sha256: None,
    };
    r.unit = Unit {
        serial: Some(serial.into()),
        serial_source: Some(SerialSource::Scanned),
        hardware: Some("0x03".into()),
        firmware: Some("1.4.2".into()),
        build: Some("7".into()),
    };
    let bad = (rng.unit() < p_fail).then(|| (rng.next() % STEPS.len() as u64) as usize);
    let mut at = t;
    for (i, (name, m, unit, low, high, mean, sigma)) in STEPS.iter().enumerate() {
        let mut value = mean + sigma * rng.normal();
        if *m == "fanCurrent" {
            value += fan_drift;
        }
        if m.ends_with("spread") {
            // A spread is never below zero.
            value = value.abs();
        }
        if bad == Some(i) {
            value = match (low, high) {
                (_, Some(h)) => h + sigma.max(0.05) * (1.0 + rng.unit()),
                (Some(l), None) => l - sigma.max(0.05) * (1.0 + rng.unit()),
                (None, None) => value,
            };
        }
        let pass = low.is_none_or(|l| value >= l) && high.is_none_or(|h| value <= h);
        let duration = 300 + (rng.next() % 900) as i64;
        r.steps.push(StepRecord {
            name: (*name).into(),
            kind: "Range".into(),
            started_ms: at,
            duration_ms: duration,
            verdict: Verdict::of(pass),
            reason: (!pass).then(|| format!("out of limits: {m}")),
            detail: format!("{m} {value:.3} {unit}"),
            measurements: vec![Measurement {
                name: (*m).into(),
                unit: (*unit).into(),
                low: *low,
                high: *high,
                value,
                pass,
            }],
            writes: Vec::new(),
        });
        at += duration;
    }
    r.finish(None);
    r.ended_ms = at;
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generation_is_deterministic_and_retests_the_failed_units() {
        let mut a = Vec::new();
        generate(200, 0, 200 * 60_000, 7, &mut |r| a.push(r));
        let mut b = Vec::new();
        generate(200, 0, 200 * 60_000, 7, &mut |r| b.push(r));
        assert_eq!(a, b);
        let failed = a.iter().filter(|r| r.verdict == Verdict::Fail).count();
        assert!(
            a.len() > 200 && failed > 0,
            "{} records, {failed} failed",
            a.len()
        );
        assert!(a.iter().all(|r| r.steps.len() == STEPS.len()));
    }
}
