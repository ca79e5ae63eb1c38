//! Whether the device behind the port answers, as this connection's frames and silences tell
//! it: what was inferred from the counters in the window is reported by the link itself
//! ([`DeviceEvent`]), when it is news.

use crate::link::{DeviceEvent, SILENT_AFTER};

/// What this connection has seen of the device.
#[derive(Debug, Default)]
pub(super) struct Liveness {
    /// A frame came from the device on this connection.
    answered: bool,
    /// Attempts unanswered since the last frame from the device.
    unanswered: u64,
}

impl Liveness {
    /// A frame came from the device: [`DeviceEvent::Answered`] when it is the first of the
    /// connection or the first after silence.
    pub(super) fn answered(&mut self) -> Option<DeviceEvent> {
        let after_silence = self.unanswered >= SILENT_AFTER;
        let news = !self.answered || after_silence;
        self.answered = true;
        self.unanswered = 0;
        news.then_some(DeviceEvent::Answered { after_silence })
    }

    /// An attempt went unanswered: [`DeviceEvent::Silent`] once [`SILENT_AFTER`] have in a row.
    pub(super) fn unanswered(&mut self) -> Option<DeviceEvent> {
        self.unanswered += 1;
        (self.unanswered >= SILENT_AFTER).then_some(DeviceEvent::Silent {
            unanswered: self.unanswered,
        })
    }

    /// A new connection, or none: nothing is known of the device.
    pub(super) fn forget(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_answer_silence_and_an_answer_after_silence_are_news_and_nothing_else_is() {
        let mut l = Liveness::default();
        assert_eq!(l.unanswered(), None);
        assert_eq!(
            l.answered(),
            Some(DeviceEvent::Answered {
                after_silence: false
            })
        );
        assert_eq!(l.answered(), None, "the device still answers: no news");
        // Two misses, then an answer: not silent.
        assert_eq!((l.unanswered(), l.unanswered()), (None, None));
        assert_eq!(l.answered(), None);
        for n in 1..SILENT_AFTER {
            assert_eq!(l.unanswered(), None, "{n}");
        }
        assert_eq!(
            l.unanswered(),
            Some(DeviceEvent::Silent {
                unanswered: SILENT_AFTER
            })
        );
        assert_eq!(
            l.unanswered(),
            Some(DeviceEvent::Silent {
                unanswered: SILENT_AFTER + 1
            })
        );
        assert_eq!(
            l.answered(),
            Some(DeviceEvent::Answered {
                after_silence: true
            })
        );
        l.forget();
        assert_eq!(
            l.answered(),
            Some(DeviceEvent::Answered {
                after_silence: false
            })
        );
    }
}
