//! The station's short sound on a verdict: PASS two rising tones, FAIL a low double buzz, so an
//! operator hears which without looking. No audio library (and no system `-dev` package): the
//! sound is a 16-bit PCM WAV made in memory ([`wav`]), written to a temporary file and played
//! by the first player this PC has (`paplay`, `pw-play`, `aplay` on Linux; `afplay` on macOS;
//! PowerShell's `Media.SoundPlayer` on Windows) on its own thread, so the window never waits.
//! A PC with no player is said once in the log (info), not as an error.
//!
//! The window holds the sound behind [`VerdictSound`], so a test counts what it asked for.

use std::sync::atomic::{AtomicBool, Ordering};

/// Samples a second in the WAV made.
pub const SAMPLE_RATE: u32 = 22_050;

/// Which sound: a passed unit's or a failed one's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tone {
    /// Two rising tones (880 Hz then 1320 Hz, 0.15 s each).
    Pass,
    /// A low double buzz (220 Hz, 0.15 s, a 0.05 s gap, 0.15 s again).
    Fail,
}

impl Tone {
    /// The tone for a verdict: `pass` true is [`Tone::Pass`].
    pub fn of(pass: bool) -> Self {
        if pass { Self::Pass } else { Self::Fail }
    }

    /// The tone's parts: (frequency Hz, 0 for silence; seconds).
    fn parts(self) -> &'static [(f32, f32)] {
        match self {
            Self::Pass => &[(880.0, 0.15), (1320.0, 0.15)],
            Self::Fail => &[(220.0, 0.15), (0.0, 0.05), (220.0, 0.15)],
        }
    }

    /// The tone's length, seconds (0.3 for PASS, 0.35 for FAIL).
    pub fn seconds(self) -> f32 {
        self.parts().iter().map(|p| p.1).sum()
    }
}

/// What the window asks for on each verdict (the sound on, once per verdict).
pub trait VerdictSound: Send {
    /// Plays `tone`, returning at once.
    fn play(&mut self, tone: Tone);
}

/// The PC's own player, on a thread per sound.
#[derive(Debug, Default)]
pub struct SystemPlayer;

impl VerdictSound for SystemPlayer {
    fn play(&mut self, tone: Tone) {
        let spawned = std::thread::Builder::new()
            .name("verdict-sound".into())
            .spawn(move || play_now(tone));
        if let Err(e) = spawned {
            log::warn!("verdict sound: no thread to play it: {e}");
        }
    }
}

/// No sound at all, whatever the box says (a screenshot tour).
#[derive(Debug, Default)]
pub struct Silent;

impl VerdictSound for Silent {
    fn play(&mut self, _tone: Tone) {}
}

/// Whether "no player" has been logged already (once per process).
static NO_PLAYER_SAID: AtomicBool = AtomicBool::new(false);

/// Writes `tone`'s WAV to a temporary file and plays it with the first player found; blocks
/// for the sound's length. The file is removed afterwards.
fn play_now(tone: Tone) {
    let file = tempfile::Builder::new()
        .prefix("botbench-verdict-")
        .suffix(".wav")
        .tempfile()
        .and_then(|mut f| {
            std::io::Write::write_all(&mut f, &wav(tone))?;
            Ok(f)
        });
    let file = match file {
        Ok(f) => f,
        Err(e) => {
            log::warn!("verdict sound: cannot write the sound's file: {e}");
            return;
        }
    };
    let path = file.path().display().to_string();
    for (program, args) in players(&path) {
        match std::process::Command::new(program)
            .args(&args)
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
        {
            Ok(status) if status.success() => return,
            Ok(status) => log::debug!("verdict sound: {program} ended with {status}"),
            Err(e) => log::debug!("verdict sound: {program}: {e}"),
        }
    }
    if !NO_PLAYER_SAID.swap(true, Ordering::Relaxed) {
        log::info!("verdict sound: no sound player on this PC (tried {PLAYERS}); silent");
    }
}

/// The players tried, as said in the log.
#[cfg(target_os = "macos")]
const PLAYERS: &str = "afplay";
/// The players tried, as said in the log.
#[cfg(windows)]
const PLAYERS: &str = "powershell";
/// The players tried, as said in the log.
#[cfg(not(any(target_os = "macos", windows)))]
const PLAYERS: &str = "paplay, pw-play, aplay";

/// The players to try for the WAV at `path`, in order: (program, arguments).
fn players(path: &str) -> Vec<(&'static str, Vec<String>)> {
    if cfg!(target_os = "macos") {
        vec![("afplay", vec![path.to_string()])]
    } else if cfg!(windows) {
        let script = format!(
            "(New-Object Media.SoundPlayer '{}').PlaySync()",
            path.replace('\'', "''")
        );
        vec![(
            "powershell",
            vec!["-NoProfile".into(), "-Command".into(), script],
        )]
    } else {
        vec![
            ("paplay", vec![path.to_string()]),
            ("pw-play", vec![path.to_string()]),
            ("aplay", vec!["-q".into(), path.to_string()]),
        ]
    }
}

/// `tone` as a WAV file's bytes: RIFF, a 16-byte `fmt ` chunk (PCM, mono, [`SAMPLE_RATE`],
/// 16 bits), then `data` with the samples (little-endian i16, half of full scale, 5 ms
/// fades so nothing clicks).
pub fn wav(tone: Tone) -> Vec<u8> {
    let samples = samples(tone);
    let data_len = u32::try_from(samples.len() * 2).unwrap_or(u32::MAX);
    let mut out = Vec::with_capacity(44 + samples.len() * 2);
    out.extend_from_slice(b"RIFF");
    out.extend_from_slice(&(36 + data_len).to_le_bytes());
    out.extend_from_slice(b"WAVEfmt ");
    out.extend_from_slice(&16u32.to_le_bytes());
    out.extend_from_slice(&1u16.to_le_bytes()); // PCM
    out.extend_from_slice(&1u16.to_le_bytes()); // mono
    out.extend_from_slice(&SAMPLE_RATE.to_le_bytes());
    out.extend_from_slice(&(SAMPLE_RATE * 2).to_le_bytes()); // bytes a second
    out.extend_from_slice(&2u16.to_le_bytes()); // bytes a frame
    out.extend_from_slice(&16u16.to_le_bytes()); // bits a sample
    out.extend_from_slice(b"data");
    out.extend_from_slice(&data_len.to_le_bytes());
    for s in samples {
        out.extend_from_slice(&s.to_le_bytes());
    }
    out
}

/// `tone`'s samples at [`SAMPLE_RATE`].
fn samples(tone: Tone) -> Vec<i16> {
    let rate = SAMPLE_RATE as f32;
    let fade = (0.005 * rate) as usize;
    let mut out = Vec::new();
    for &(hz, secs) in tone.parts() {
        let n = (secs * rate).round() as usize;
        for i in 0..n {
            let edge = i.min(n - 1 - i).min(fade) as f32 / fade as f32;
            let wave = if hz == 0.0 {
                0.0
            } else {
                (std::f32::consts::TAU * hz * i as f32 / rate).sin()
            };
            // A buzz is the sine clipped towards a square: low, rough, unlike PASS.
            let wave = match tone {
                Tone::Fail => (wave * 3.0).clamp(-1.0, 1.0),
                Tone::Pass => wave,
            };
            out.push((wave * edge * 0.5 * f32::from(i16::MAX)) as i16);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u16_at(b: &[u8], at: usize) -> u16 {
        u16::from_le_bytes([b[at], b[at + 1]])
    }

    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    /// The WAV's samples, its header read back and checked field by field.
    fn read_back(bytes: &[u8]) -> Vec<i16> {
        assert_eq!(&bytes[0..4], b"RIFF");
        assert_eq!(u32_at(bytes, 4) as usize, bytes.len() - 8, "RIFF size");
        assert_eq!(&bytes[8..16], b"WAVEfmt ");
        assert_eq!(u32_at(bytes, 16), 16, "fmt chunk size");
        assert_eq!(u16_at(bytes, 20), 1, "PCM");
        assert_eq!(u16_at(bytes, 22), 1, "mono");
        assert_eq!(u32_at(bytes, 24), SAMPLE_RATE);
        assert_eq!(u32_at(bytes, 28), SAMPLE_RATE * 2, "bytes a second");
        assert_eq!(u16_at(bytes, 32), 2, "block align");
        assert_eq!(u16_at(bytes, 34), 16, "bits a sample");
        assert_eq!(&bytes[36..40], b"data");
        assert_eq!(u32_at(bytes, 40) as usize, bytes.len() - 44, "data size");
        bytes[44..]
            .chunks_exact(2)
            .map(|c| i16::from_le_bytes([c[0], c[1]]))
            .collect()
    }

    /// Sign changes a second in `part` (twice the frequency).
    fn crossings_a_second(part: &[i16]) -> f32 {
        let changes = part.windows(2).filter(|w| (w[0] < 0) != (w[1] < 0)).count();
        changes as f32 * SAMPLE_RATE as f32 / part.len() as f32
    }

    #[test]
    fn the_wav_header_and_length_read_back_right() {
        for (tone, secs) in [(Tone::Pass, 0.3), (Tone::Fail, 0.35)] {
            let samples = read_back(&wav(tone));
            let want = (secs * SAMPLE_RATE as f32).round() as usize;
            assert!(
                samples.len().abs_diff(want) <= 2,
                "{tone:?}: {}",
                samples.len()
            );
            let loudest = samples.iter().map(|s| s.unsigned_abs()).max().unwrap_or(0);
            assert!(
                (8_000..=16_384).contains(&loudest),
                "{tone:?}: peak {loudest}"
            );
            // Faded in and out: no click at either end.
            assert!(
                samples[0].unsigned_abs() < 100 && samples[samples.len() - 1].unsigned_abs() < 100
            );
        }
    }

    #[test]
    fn pass_rises_and_fail_is_a_low_double_buzz() {
        let pass = read_back(&wav(Tone::Pass));
        let (first, second) = pass.split_at(pass.len() / 2);
        let (lo, hi) = (crossings_a_second(first), crossings_a_second(second));
        assert!(
            (1700.0..1820.0).contains(&lo),
            "first tone {lo} crossings/s"
        );
        assert!(
            (2580.0..2700.0).contains(&hi),
            "second tone {hi} crossings/s"
        );
        let fail = read_back(&wav(Tone::Fail));
        let buzz = crossings_a_second(&fail[..fail.len() / 3]);
        assert!((400.0..480.0).contains(&buzz), "buzz {buzz} crossings/s");
        // The gap between the two buzzes is silent.
        let gap_start = (0.16 * SAMPLE_RATE as f32) as usize;
        let gap = &fail[gap_start..gap_start + (0.03 * SAMPLE_RATE as f32) as usize];
        assert!(gap.iter().all(|&s| s == 0), "the gap is silent");
    }
}
