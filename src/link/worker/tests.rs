//! The worker against ports written here: a device that never answers, on a host that is held
//! up (a loaded computer) or not.

use crate::link::request::{ExchangeError, Request};
use crate::link::{Link, LinkError, LinkOptions, Opener, Transport};
use crate::profile::Registry;
use std::time::{Duration, Instant};

/// How long past each read's deadline the held-up host wakes.
const LATE_BY: Duration = Duration::from_millis(30);

/// A port nothing ever answers on; with `held_up`, every read that finds nothing returns that
/// long after its deadline (the link's thread not scheduled in time: a loaded computer).
struct Silent {
    held_up: Duration,
}

impl Transport for Silent {
    fn write(&mut self, _bytes: &[u8]) -> Result<(), LinkError> {
        Ok(())
    }
    fn read(&mut self, _buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let wake = deadline + self.held_up;
        std::thread::sleep(wake.saturating_duration_since(Instant::now()));
        Ok(0)
    }
    fn set_baud(&mut self, _baud: u32) -> Result<(), LinkError> {
        Ok(())
    }
    fn baud(&self) -> u32 {
        115_200
    }
    fn clear_input(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    fn describe(&self) -> String {
        "a silent port".into()
    }
}

/// A link to a silent window cleaner (no session: only the test's requests go out).
fn silent_link(held_up: Duration) -> Link {
    let profile = Registry::builtin()
        .and_then(|r| r.get("window-cleaner"))
        .expect("the built-in window cleaner profile");
    let opener: Opener = Box::new(move || Ok(Box::new(Silent { held_up }) as Box<dyn Transport>));
    let options = LinkOptions {
        start_session: false,
        reconnect: false,
        ..LinkOptions::default()
    };
    Link::open(opener, profile, options, None).expect("the port opens")
}

/// A request that went unanswered while this computer was held up past its deadlines says so,
/// with how long (issue 25, item 4e).
#[test]
fn a_timeout_while_the_host_was_held_up_says_the_computer_was_held_up() {
    let link = silent_link(LATE_BY);
    let err = link
        .client()
        .request(Request::new(130, Vec::new()).attempts(2))
        .expect_err("nothing answers");
    let late = err.host_late();
    assert!(
        matches!(err, ExchangeError::Timeout { attempts: 2, .. }),
        "{err:?}"
    );
    assert!(
        late.is_some_and(|l| l >= LATE_BY),
        "the largest lateness of the exchange: {late:?}"
    );
    let said = err.to_string();
    assert!(
        said.starts_with("no answer to MSP_GET_PWMVALUE (130) after 2 attempt(s)"),
        "{said}"
    );
    assert!(
        said.contains(" — this computer was held up ")
            && said.contains(" ms past the answer's deadline (a loaded computer: the answer may have come while it was): close other programs and retry"),
        "{said}"
    );
}

/// A host a few milliseconds late (common on a busy desktop; the link looks once more when it
/// wakes late) is not said as held up: the silence is the device's.
#[test]
fn a_timeout_a_few_milliseconds_late_does_not_blame_the_computer() {
    let link = silent_link(Duration::from_millis(5));
    let err = link
        .client()
        .request(Request::new(130, Vec::new()).attempts(2))
        .expect_err("nothing answers");
    assert_eq!(err.host_late(), None, "{err:?}");
    assert!(!err.to_string().contains("held up"), "{err}");
}
