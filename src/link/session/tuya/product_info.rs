//! The MCU's product info (the answer to 0x01), read leniently.

use serde::Serialize;

/// The MCU's product info (0x01), read leniently.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ProductInfo {
    /// Product id (`p`).
    pub pid: Option<String>,
    /// MCU firmware version (`v`).
    pub version: Option<String>,
    /// Configuration mode (`m`: 0 default, 1 low power, 2 special).
    pub mode: Option<i64>,
    /// The text as received.
    pub raw: String,
    /// Why it could not be read as JSON, if it could not.
    pub error: Option<String>,
}

/// Reads product info: JSON like `{"p":"…","v":"1.0.0","m":0}`, other keys ignored; malformed
/// text is kept raw with the reason.
pub fn parse_product_info(data: &[u8]) -> ProductInfo {
    let raw = String::from_utf8_lossy(data).into_owned();
    match serde_json::from_slice::<serde_json::Value>(data) {
        Ok(serde_json::Value::Object(map)) => ProductInfo {
            pid: map.get("p").and_then(|v| v.as_str()).map(str::to_string),
            version: map.get("v").and_then(|v| v.as_str()).map(str::to_string),
            mode: map.get("m").and_then(|v| v.as_i64()),
            raw,
            error: None,
        },
        Ok(_) => ProductInfo {
            pid: None,
            version: None,
            mode: None,
            raw,
            error: Some("not a JSON object".into()),
        },
        Err(e) => ProductInfo {
            pid: None,
            version: None,
            mode: None,
            raw,
            error: Some(e.to_string()),
        },
    }
}
