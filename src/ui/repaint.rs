//! How often the window redraws on its own, without input. Under software rendering (Mesa
//! llvmpipe, as on a line PC without a GPU) most of a frame's cost is the window's pixels (see
//! [`super::backdrop`] for how few it shades), so the rate is what costs: a live view redraws at
//! [`LIVE`], background worker events at most every [`BACKGROUND`], and nothing else redraws
//! until the user acts. Measured by `.ci/window_cpu.sh`.

use std::time::Duration;

/// A live view (a plot following streaming data, the packet monitor, a running job's progress)
/// redraws this often, whatever the poll rate: 10 Hz, enough for the eye to follow a trace (at
/// the default 60 s window a trace moves about 1.5 px a frame). The cost follows the rate:
/// measured on the telemetry panel at 1200×780 under llvmpipe (on an earlier machine, while the
/// panels still painted their fills), 30 Hz took 65 % of a core, 15 Hz 31 %, 10 Hz about 21 %.
pub const LIVE: Duration = Duration::from_millis(100);

/// Worker events that arrive while no live view is shown (polled telemetry behind another
/// panel, the link's counters) redraw the window at most this often. Job results and input
/// redraw at once.
pub const BACKGROUND: Duration = Duration::from_millis(500);
