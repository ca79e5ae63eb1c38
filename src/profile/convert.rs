//! Conversions of raw values that are not `raw × scale`: a servo's thermistor reading to °C.

use super::model::Conversion;

/// 25 °C in kelvin: the thermistor's nominal point.
const T25_K: f64 = 298.15;
/// 0 °C in kelvin.
const ZERO_C_K: f64 = 273.15;

impl Conversion {
    /// The value a raw reading stands for, or `None` where the conversion is undefined (a
    /// thermistor reading of 0, or at or above full scale: an open or shorted sensor).
    pub fn apply(self, raw: i64) -> Option<f64> {
        match self {
            Conversion::Ntc { beta, full_scale } => {
                let full = full_scale as f64;
                let x = raw as f64;
                if raw <= 0 || x >= full || beta <= 0.0 {
                    return None;
                }
                let t = 1.0 / ((x / (full - x)).ln() / beta + 1.0 / T25_K) - ZERO_C_K;
                t.is_finite().then_some(t)
            }
        }
    }

    /// The raw reading nearest to `value`, or `None` where no reading stands for it.
    pub fn invert(self, value: f64) -> Option<i64> {
        match self {
            Conversion::Ntc { beta, full_scale } => {
                let full = full_scale as f64;
                let kelvin = value + ZERO_C_K;
                if !(kelvin > 0.0 && value.is_finite()) || beta <= 0.0 {
                    return None;
                }
                let r = (beta * (1.0 / kelvin - 1.0 / T25_K)).exp();
                let raw = (full * r / (1.0 + r)).round();
                (raw >= 1.0 && raw < full).then_some(raw as i64)
            }
        }
    }

    /// Digits after the decimal point worth showing.
    pub fn decimals(self) -> usize {
        match self {
            Conversion::Ntc { .. } => 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SDK: Conversion = Conversion::Ntc {
        beta: 3435.0,
        full_scale: 4096,
    };

    #[test]
    fn the_sdk_formula_at_the_points_its_readme_lists() {
        // tests/sdk/README.md: raw 2048 = 25 °C, 1779 = 32 °C, 835 = 65 °C, 368 = 100 °C,
        // 32 = 241.3 °C, 3038 = 0 °C.
        for (raw, c) in [
            (2048, 25.0),
            (1779, 32.0),
            (835, 65.0),
            (368, 100.0),
            (32, 241.3),
            (3038, 0.0),
        ] {
            let t = SDK.apply(raw).unwrap();
            assert!((t - c).abs() < 0.1, "raw {raw}: {t} °C, want {c}");
            assert!(
                SDK.invert(c).unwrap().abs_diff(raw) <= 2,
                "{c} °C back to raw {raw}"
            );
        }
        assert_eq!(SDK.apply(0), None);
        assert_eq!(SDK.apply(4096), None);
        assert_eq!(SDK.apply(5000), None);
        assert_eq!(SDK.invert(-300.0), None);
    }
}
