//! The simulated vacuum MCU against Tuya's own MCU SDK, frame by frame: for the same module
//! frames (0x06 data-point commands) it sends exactly the frames the SDK sends.
//!
//! The expected frames are derived by hand from the SDK's public C source, MCU SDK v2.5.6 (as in
//! Tuya-Community/tuya-iotos-embeded-mcu-demo-wifi-ble-stm32_lcd_wb3s, `mcu_sdk/system.c` and
//! `mcu_sdk/mcu_api.c`; the `dp_download_*_handle` templates of the generated `protocol.c`):
//! - `data_handle`, case `DATA_QUERT_CMD`: the data points of the frame are walked in order,
//!   `i += dp_len + 4`, each handed to `data_point_handle`;
//! - `data_point_handle`: a data point whose type byte differs from its `download_cmd` entry gets
//!   no handler, hence no report;
//! - a `dp_download_*_handle` reports the value it received, once: `mcu_dp_bool_update(DPID,
//!   value)` writes `dpid, DP_TYPE_BOOL, 0x00, 0x01, value ? 1 : 0` (a bool 2 is reported 1),
//!   `mcu_dp_enum_update` `dpid, DP_TYPE_ENUM, 0x00, 0x01, value`, each as its own
//!   `wifi_uart_write_frame(STATE_UPLOAD_CMD, MCU_TX_VER = 0x03, len)`;
//! - report-only data points have no download handler, so no report either.
//!
//! What the vacuum's own rules change afterwards (its status when the power goes off) is not
//! the SDK's answer: the simulator reports it from its next tick.

use botbench::protocol::hex;
use botbench::sim::Device;
use botbench::sim::tuya_mcu::{TuyaConfig, TuyaMcu};
use std::time::Instant;

/// (what the module sends, what the SDK answers: one frame each), hex.
const VECTORS: &[(&str, &[&str])] = &[
    // power = 0, mode = 2 (auto clean), find robot = 1: three reports, the values received.
    (
        "55 aa 00 06 00 0f 01 01 00 01 00 03 04 00 01 02 0d 01 00 01 01 31",
        &[
            "55 aa 03 07 00 05 01 01 00 01 00 11",
            "55 aa 03 07 00 05 03 04 00 01 02 18",
            "55 aa 03 07 00 05 0d 01 00 01 01 1e",
        ],
    ),
    // mode = 4 (mop): its report alone.
    (
        "55 aa 00 06 00 05 03 04 00 01 04 16",
        &["55 aa 03 07 00 05 03 04 00 01 04 1a"],
    ),
    // power sent as an enum (its definition is a bool): no handler, no report; suction = 0 is
    // answered.
    (
        "55 aa 00 06 00 0a 01 04 00 01 00 0e 04 00 01 00 28",
        &["55 aa 03 07 00 05 0e 04 00 01 00 21"],
    ),
    // find robot = 2 is reported as 1 (mcu_dp_bool_update), direction = 2 as received.
    (
        "55 aa 00 06 00 0a 0d 01 00 01 02 04 04 00 01 02 2b",
        &[
            "55 aa 03 07 00 05 0d 01 00 01 01 1e",
            "55 aa 03 07 00 05 04 04 00 01 02 19",
        ],
    ),
    // battery (report only) = 50 gets nothing; clean switch = 1 is answered.
    (
        "55 aa 00 06 00 0d 06 02 00 04 00 00 00 32 02 01 00 01 01 55",
        &["55 aa 03 07 00 05 02 01 00 01 01 13"],
    ),
];

fn bytes(text: &str) -> Vec<u8> {
    hex::parse(text).expect("hex")
}

#[test]
fn each_data_point_of_a_command_gets_exactly_the_sdks_one_report() {
    // One MCU for all: the answers do not depend on what it held before.
    let mut mcu = TuyaMcu::new(TuyaConfig {
        baud: None,
        ..TuyaConfig::default()
    });
    let now = Instant::now();
    for (module, sdk) in VECTORS {
        let got: Vec<String> = mcu
            .receive(&bytes(module), 9600, now)
            .into_iter()
            .map(|o| hex::format(&o.bytes))
            .collect();
        assert_eq!(got, *sdk, "answers to {module}");
        // What the rules changed comes after, from the tick; never the commanded points again.
        mcu.tick(now);
    }
}

#[test]
fn the_vacuum_holds_what_one_frame_commanded_and_reports_what_followed_in_order() {
    let mut mcu = TuyaMcu::new(TuyaConfig {
        baud: None,
        ..TuyaConfig::default()
    });
    let now = Instant::now();
    // Start cleaning (clean switch on), then one frame: power 0, mode 2, find robot 1.
    mcu.receive(&bytes(VECTORS[4].0), 9600, now);
    mcu.tick(now);
    mcu.receive(&bytes(VECTORS[0].0), 9600, now);
    let dp = |id: u8| format!("{:?}", mcu.dp(id).expect("a data point"));
    // What the frame said stands: powered off, mode 2 kept, find robot on.
    assert_eq!(
        (dp(1), dp(3), dp(13)),
        ("Bool(false)".into(), "Enum(2)".into(), "Bool(true)".into())
    );
    // A robot powered off does not clean: the clean switch and the status follow, reported
    // after the answers, in the order they changed.
    let followed: Vec<String> = mcu
        .tick(now)
        .into_iter()
        .map(|o| hex::format(&o.bytes))
        .collect();
    assert_eq!(
        followed,
        [
            "55 aa 03 07 00 05 02 01 00 01 00 12",
            "55 aa 03 07 00 05 05 04 00 01 00 18"
        ]
    );
}
