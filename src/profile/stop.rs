//! The profile's STOP: which commands, with which values, bring the robot to rest (motors,
//! fan, spray off). Checked at load; read by the window's STOP button, the self-test's safe
//! state (ops' `stop.rs`) and the "running" indicator, which tells a command that starts
//! something from the same command stopping it.

use super::codec::Input;
use super::model::{Command, CommandKind, Initiator, Profile};
use super::validate::{Issue, issue};
use super::value::Value;
use crate::document::Step::{Index, Key};

impl Profile {
    /// The STOP's commands in order, each with its inputs (display text, as the profile
    /// writes them). Empty when the profile names no STOP.
    pub fn stop_commands(&self) -> Vec<(&Command, Vec<(String, Input)>)> {
        self.stop
            .iter()
            .filter_map(|s| {
                let cmd = self.command(&s.command)?;
                let inputs = s
                    .values
                    .iter()
                    .map(|(k, v)| (k.clone(), Input::Text(v.clone())))
                    .collect();
                Some((cmd, inputs))
            })
            .collect()
    }

    /// The raw values (by field ident) that the STOP sends with command `id`, or `None` when
    /// the command is not part of the STOP.
    pub fn stop_values(&self, id: u8) -> Option<Vec<(String, Value)>> {
        let s = self
            .stop
            .iter()
            .find(|s| self.command(&s.command).is_some_and(|c| c.id == id))?;
        let cmd = self.command_by_id(id)?;
        cmd.request
            .iter()
            .map(|f| {
                let text = s
                    .values
                    .iter()
                    .find(|(k, _)| k.eq_ignore_ascii_case(&f.ident))?
                    .1;
                Some((f.ident.clone(), f.parse(text).ok()?))
            })
            .collect()
    }

    /// Whether sending command `id` with `inputs` is what the STOP sends for it (it brings the
    /// robot to rest, so it needs no "the robot will move" confirmation).
    pub fn is_stop(&self, id: u8, inputs: &[(String, Input)]) -> bool {
        let Some(stop) = self.stop_values(id) else {
            return false;
        };
        let Some(cmd) = self.command_by_id(id) else {
            return false;
        };
        stop.iter().all(|(k, want)| {
            let Some(f) = cmd.request.iter().find(|f| &f.ident == k) else {
                return false;
            };
            inputs.iter().any(|(name, v)| {
                name.eq_ignore_ascii_case(k)
                    && match v {
                        Input::Text(t) => f.parse(t).ok().as_ref() == Some(want),
                        Input::Raw(r) => r == want,
                    }
            })
        })
    }
}

/// Checks the profile's STOP: each command exists, is sent by the host (an Action or a Set),
/// appears once, and every request field has a value it takes (no other names).
pub(super) fn check_stop(p: &Profile) -> Result<(), Issue> {
    let mut seen = Vec::new();
    for (i, s) in p.stop.iter().enumerate() {
        let at = |k| vec![Key("stop"), Index(i), Key(k)];
        let Some(cmd) = p.command(&s.command) else {
            return Err(issue(
                at("command"),
                format!("STOP names no command '{}'", s.command),
            ));
        };
        if !matches!(cmd.kind, CommandKind::Action | CommandKind::Set)
            || cmd.initiator != Initiator::Host
        {
            return Err(issue(
                at("command"),
                format!(
                    "{}: a STOP command must be an Action or a Set the host sends",
                    cmd.ident
                ),
            ));
        }
        if seen.contains(&cmd.id) {
            return Err(issue(
                at("command"),
                format!("{} is listed twice in STOP", cmd.ident),
            ));
        }
        seen.push(cmd.id);
        for name in s.values.keys() {
            if !cmd
                .request
                .iter()
                .any(|f| f.ident.eq_ignore_ascii_case(name))
            {
                return Err(issue(
                    at("values"),
                    format!("{} has no request field '{name}'", cmd.ident),
                ));
            }
        }
        for f in &cmd.request {
            let Some((_, text)) = s
                .values
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case(&f.ident))
            else {
                return Err(issue(
                    at("values"),
                    format!("{}: STOP gives no value for '{}'", cmd.ident, f.ident),
                ));
            };
            if let Err(e) = f.parse(text) {
                return Err(issue(at("values"), format!("{}: {e}", cmd.ident)));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::profile::Registry;

    #[test]
    fn the_window_cleaner_stops_motor_fan_and_spray() {
        let p = Registry::load().unwrap().get("window-cleaner").unwrap();
        let idents: Vec<&str> = p
            .stop_commands()
            .iter()
            .map(|(c, _)| c.ident.as_str())
            .collect();
        assert_eq!(idents, ["MSP_SET_MOTOR", "MSP_SET_FAN", "MSP_SET_SPRAY"]);
        assert_eq!(
            p.stop_values(211),
            Some(vec![("pwm".into(), crate::profile::Value::Int(0))])
        );
        assert_eq!(p.stop_values(208), None, "voice is not part of STOP");
    }

    #[test]
    fn a_stop_naming_a_missing_field_value_fails_to_load() {
        let src = include_str!("../../assets/profiles/window-cleaner.ron").replace(
            r#"(command: "MSP_SET_FAN", values: {"pwm": "0"})"#,
            r#"(command: "MSP_SET_FAN", values: {"pwm": "101"})"#,
        );
        let err = crate::profile::registry::parse("window-cleaner.ron", &src, None).unwrap_err();
        assert!(err.to_string().contains("MSP_SET_FAN"), "{err}");
        assert!(err.to_string().contains("out of range"), "{err}");
    }
}
