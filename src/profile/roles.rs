//! Roles: what code asks a profile for instead of knowing numbers. A command or a servo
//! parameter says what it is for (the MSP core, the solar drive and heartbeat, the servo's id,
//! baud option and serial number), and code finds it by that role, so a firmware variant that
//! moves one is an edited profile, not a new build.

use super::model::{Access, Command, CommandKind, PanelKind, Param, Profile, Protocol};
use super::validate::{Issue, issue};
use crate::document::Step::{Index, Key};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What an MSP command is for, beyond its kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CommandRole {
    /// A command of the MSP core device (ping, version, power state, build info, firmware
    /// transfer; seed: 核心命令 1-9): the device panel shows it, telemetry never polls it.
    Core,
    /// The drive command whose first field is a signed speed (solar cleanbot CMD_SET_SPEED): the
    /// solar panel's speed control, and what its STOP and dead-man outcome are shown under.
    Drive,
    /// The robot's own heartbeat interval, seconds (solar cleanbot CMD_SET_HEARTBEAT): set to the
    /// dead-man's period when it is armed.
    Heartbeat,
}

/// What a servo parameter is for.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamRole {
    /// The servo's own id (the seed's parameter 34): ID provisioning writes it.
    ServoId,
    /// The baud-rate option (the seed's parameter 36): each option's rate in baud. Every label
    /// of the parameter has a rate here and every rate a label.
    BaudOption {
        /// Option value → baud rate.
        rates: BTreeMap<u8, u32>,
    },
    /// The servo's serial number (the seed's parameter 8): the provisioning log records it, a
    /// scan shows it.
    SerialNumber,
    /// The servo's model (the seed's parameter 6, 舵机型号): a scan shows it.
    ServoType,
    /// The servo's firmware version (the seed's parameter 7): a scan shows it.
    FirmwareVersion,
    /// The supply voltage in mV (the seed's parameter 1): a scan shows it.
    Voltage,
    /// The temperature (the seed's parameter 4), raw: a scan shows it as the parameter's field
    /// displays it (°C, or a converted thermistor reading).
    Temperature,
    /// The raw status byte (the seed's parameter 5): a scan shows it in hex.
    Status,
}

impl ParamRole {
    fn same_kind(&self, other: &ParamRole) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other)
    }

    fn name(&self) -> &'static str {
        match self {
            ParamRole::ServoId => "ServoId",
            ParamRole::BaudOption { .. } => "BaudOption",
            ParamRole::SerialNumber => "SerialNumber",
            ParamRole::ServoType => "ServoType",
            ParamRole::FirmwareVersion => "FirmwareVersion",
            ParamRole::Voltage => "Voltage",
            ParamRole::Temperature => "Temperature",
            ParamRole::Status => "Status",
        }
    }
}

impl Profile {
    /// The command with `role` (at most one has each of Drive and Heartbeat).
    pub fn command_with_role(&self, role: CommandRole) -> Option<&Command> {
        self.commands.iter().find(|c| c.role == Some(role))
    }

    /// Whether `command` belongs to the MSP core (its role is [`CommandRole::Core`]).
    pub fn is_core(&self, command: &Command) -> bool {
        command.role == Some(CommandRole::Core)
    }

    /// The servo parameter with the id role ([`ParamRole::ServoId`]).
    pub fn servo_id_param(&self) -> Option<&Param> {
        self.param_with_role(&ParamRole::ServoId)
    }

    /// The servo parameter with the serial-number role ([`ParamRole::SerialNumber`]).
    pub fn serial_number_param(&self) -> Option<&Param> {
        self.param_with_role(&ParamRole::SerialNumber)
    }

    /// The baud-option parameter and its option → baud table, options in ascending order.
    pub fn baud_option_param(&self) -> Option<(&Param, &BTreeMap<u8, u32>)> {
        self.params.iter().find_map(|p| match &p.role {
            Some(ParamRole::BaudOption { rates }) => Some((p, rates)),
            _ => None,
        })
    }

    /// The baud rates the servos take, in option order; empty when the profile has no
    /// baud-option parameter.
    pub fn servo_bauds(&self) -> Vec<u32> {
        self.baud_option_param()
            .map(|(_, rates)| rates.values().copied().collect())
            .unwrap_or_default()
    }

    /// The baud rate of a baud-option value, if the profile has it.
    pub fn baud_of_option(&self, option: u8) -> Option<u32> {
        self.baud_option_param()?.1.get(&option).copied()
    }

    /// The baud-option value of a baud rate, if the profile has it.
    pub fn option_of_baud(&self, baud: u32) -> Option<u8> {
        self.baud_option_param()?
            .1
            .iter()
            .find(|(_, b)| **b == baud)
            .map(|(o, _)| *o)
    }

    /// The servo parameter with `role` (for [`ParamRole::BaudOption`], whatever its rates),
    /// if the profile gives one.
    pub fn param_with_role(&self, role: &ParamRole) -> Option<&Param> {
        self.params
            .iter()
            .find(|p| p.role.as_ref().is_some_and(|r| r.same_kind(role)))
    }
}

/// Checks the roles: at most one command or parameter per role, roles on the protocols and
/// kinds they belong to, a drive and heartbeat with a first field to write, a writable id and
/// baud parameter, and a baud table that matches the parameter's labels.
pub(super) fn check_roles(p: &Profile) -> Result<(), Issue> {
    let mut seen: Vec<CommandRole> = Vec::new();
    for (i, c) in p.commands.iter().enumerate() {
        let Some(role) = c.role else { continue };
        let at = || vec![Key("commands"), Index(i), Key("role")];
        if p.protocol != Protocol::Msp {
            return Err(issue(at(), "command roles are for MSP profiles only"));
        }
        if role != CommandRole::Core {
            if seen.contains(&role) {
                return Err(issue(at(), format!("a second command with role {role:?}")));
            }
            seen.push(role);
            if c.kind != CommandKind::Action || c.request.is_empty() {
                return Err(issue(
                    at(),
                    format!("a {role:?} command must be an Action with a request field to set"),
                ));
            }
        }
    }
    let mut kinds: Vec<&ParamRole> = Vec::new();
    for (i, param) in p.params.iter().enumerate() {
        let Some(role) = &param.role else { continue };
        let at = || vec![Key("params"), Index(i), Key("role")];
        if kinds.iter().any(|k| k.same_kind(role)) {
            return Err(issue(
                at(),
                format!("a second parameter with role {}", role.name()),
            ));
        }
        kinds.push(role);
        let writable = param.access == Access::ReadWrite;
        match role {
            ParamRole::ServoId | ParamRole::BaudOption { .. } if !writable => {
                return Err(issue(
                    at(),
                    format!("the {} parameter must be ReadWrite", role.name()),
                ));
            }
            ParamRole::BaudOption { rates } => {
                let labels: Vec<u8> = param
                    .field
                    .labels
                    .iter()
                    .filter_map(|l| u8::try_from(l.value).ok())
                    .collect();
                let options: Vec<u8> = rates.keys().copied().collect();
                if rates.is_empty() || labels != options {
                    return Err(issue(
                        at(),
                        format!(
                            "the baud table's options {options:?} must be the parameter's label \
                             values {labels:?}, each with its rate"
                        ),
                    ));
                }
                if let Some((o, b)) = rates.iter().find(|(_, b)| **b == 0) {
                    return Err(issue(at(), format!("option {o} has baud rate {b}")));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Checks that each panel the profile lists has what it shows, on the protocol it belongs to.
pub(super) fn check_panel_needs(p: &Profile) -> Result<(), Issue> {
    for (i, rule) in p.panels.iter().enumerate() {
        let at = || vec![Key("panels"), Index(i), Key("panel")];
        let has = |k: CommandKind| p.commands.iter().any(|c| c.kind == k);
        let msp = p.protocol == Protocol::Msp;
        let need: Option<&str> = match rule.panel {
            PanelKind::Device | PanelKind::SelfTest if !msp => Some("an MSP profile"),
            PanelKind::Tuning if !has(CommandKind::Set) => Some("a Set command"),
            PanelKind::Telemetry if p.plots.is_empty() => Some("a plot"),
            PanelKind::Presets if !p.commands.iter().any(|c| c.pair.is_some()) => {
                Some("a Get/Set pair")
            }
            PanelKind::Actions if !has(CommandKind::Action) => Some("an Action command"),
            PanelKind::Solar if p.command_with_role(CommandRole::Drive).is_none() => {
                Some("a command with role Drive")
            }
            PanelKind::ServoBench if p.protocol != Protocol::Servo => Some("a servo profile"),
            PanelKind::TuyaConsole if p.protocol != Protocol::Tuya => Some("a Tuya profile"),
            _ => None,
        };
        if let Some(need) = need {
            return Err(issue(at(), format!("panel {:?} needs {need}", rule.panel)));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::registry::{BUILTIN, parse};

    fn builtin(name: &str) -> &'static str {
        BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .expect("built-in")
            .1
    }

    /// `name`'s built-in text with `from` replaced by `to` (once, checked).
    fn edited(name: &str, from: &str, to: &str) -> String {
        let src = builtin(name);
        assert!(src.contains(from), "test setup: '{from}' not in {name}");
        src.replacen(from, to, 1)
    }

    fn load(name: &str, src: &str) -> Result<Profile, crate::profile::ProfileError> {
        parse(&format!("{name}.ron"), src, None)
    }

    #[test]
    fn the_builtin_profiles_give_every_role_code_asks_for() {
        let solar = load("solar-cleanbot", builtin("solar-cleanbot")).expect("loads");
        let drive = solar.command_with_role(CommandRole::Drive).expect("drive");
        assert_eq!(drive.ident, "CMD_SET_SPEED");
        let hb = solar.command_with_role(CommandRole::Heartbeat).expect("hb");
        assert_eq!(hb.ident, "CMD_SET_HEARTBEAT");
        let core: Vec<&str> = solar
            .commands
            .iter()
            .filter(|c| solar.is_core(c))
            .map(|c| c.ident.as_str())
            .collect();
        assert_eq!(core.len(), 9, "{core:?}");
        assert!(core.iter().all(|i| i.starts_with("CMD_")), "{core:?}");

        let servo = load("servo", builtin("servo")).expect("loads");
        assert_eq!(servo.servo_id_param().map(|p| p.id), Some(34));
        assert_eq!(servo.serial_number_param().map(|p| p.id), Some(8));
        assert_eq!(servo.baud_option_param().map(|(p, _)| p.id), Some(36));
        assert_eq!(
            servo.servo_bauds(),
            [
                9600, 19200, 38400, 57600, 115_200, 250_000, 500_000, 1_000_000
            ]
        );
        assert_eq!(servo.baud_of_option(5), Some(115_200));
        assert_eq!(servo.option_of_baud(1_000_000), Some(8));
        assert_eq!(servo.option_of_baud(230_400), None);
    }

    #[test]
    fn a_firmware_that_moves_the_drive_command_is_an_edited_profile() {
        let src = edited(
            "solar-cleanbot",
            "kind: Action, confirm: true, role: Some(Drive),",
            "kind: Action, confirm: true,",
        );
        let src = src.replacen(
            "id: 99, ident: \"CMD_SET_ROTATE\", name: (en: \"Rotate\", zh: \"设置旋转角度值\"),\n            kind: Action, confirm: true,",
            "id: 99, ident: \"CMD_SET_ROTATE\", name: (en: \"Rotate\", zh: \"设置旋转角度值\"),\n            kind: Action, confirm: true, role: Some(Drive),",
            1,
        );
        let p = load("solar-cleanbot", &src).expect("loads");
        let drive = p.command_with_role(CommandRole::Drive).expect("drive");
        assert_eq!(drive.id, 99);
    }

    #[test]
    fn inconsistent_roles_are_refused_with_what_is_wrong() {
        // Two drives.
        let src = edited(
            "solar-cleanbot",
            "kind: Action, role: Some(Heartbeat),",
            "kind: Action, role: Some(Drive),",
        );
        let err = load("solar-cleanbot", &src).unwrap_err();
        assert!(
            err.message.contains("second command with role Drive"),
            "{err}"
        );

        // A solar panel with no drive to control.
        let src = edited(
            "solar-cleanbot",
            "kind: Action, confirm: true, role: Some(Drive),",
            "kind: Action, confirm: true,",
        );
        let err = load("solar-cleanbot", &src).unwrap_err();
        assert!(
            err.message
                .contains("panel Solar needs a command with role Drive"),
            "{err}"
        );

        // A baud table that forgets an option the parameter has.
        let src = edited("servo", " 8: 1000000,", "");
        let err = load("servo", &src).unwrap_err();
        assert!(
            err.message.contains("must be the parameter's label values"),
            "{err}"
        );

        // Two id parameters.
        let src = edited(
            "servo",
            "(id: 34, access: ReadWrite, role: Some(ServoId),",
            "(id: 34, access: ReadWrite, role: Some(SerialNumber),",
        );
        let err = load("servo", &src).unwrap_err();
        assert!(
            err.message
                .contains("second parameter with role SerialNumber"),
            "{err}"
        );

        // Two temperatures for a scan to show.
        let src = edited(
            "servo",
            "(id: 2, access: ReadOnly, field:",
            "(id: 2, access: ReadOnly, role: Some(Temperature), field:",
        );
        let err = load("servo", &src).unwrap_err();
        assert!(
            err.message
                .contains("second parameter with role Temperature"),
            "{err}"
        );
        // Located at the second one.
        let at = src
            .match_indices("role: Some(Temperature)")
            .nth(1)
            .expect("two")
            .0;
        assert_eq!(err.line, src[..at].matches('\n').count() + 1, "{err}");

        // An id that cannot be written.
        let src = edited(
            "servo",
            "(id: 8, access: ReadOnly, role: Some(SerialNumber),",
            "(id: 8, access: ReadOnly, role: Some(ServoId),",
        );
        let err = load("servo", &src).unwrap_err();
        assert!(
            err.message.contains("ServoId parameter must be ReadWrite"),
            "{err}"
        );
    }

    #[test]
    fn a_panel_is_refused_where_it_has_nothing_to_show() {
        let src = edited(
            "servo",
            "(panel: ServoBench),",
            "(panel: ServoBench),\n        (panel: Solar),",
        );
        let err = load("servo", &src).unwrap_err();
        assert!(
            err.message
                .contains("panel Solar needs a command with role Drive"),
            "{err}"
        );

        let src = edited(
            "tuya-vacuum",
            "(panel: TuyaConsole),",
            "(panel: ServoBench),",
        );
        let err = load("tuya-vacuum", &src).unwrap_err();
        assert!(err.message.contains("needs a servo profile"), "{err}");

        let src = edited(
            "servo",
            "(panel: ServoBench),",
            "(panel: ServoBench, flag: Some(1)),",
        );
        let err = load("servo", &src).unwrap_err();
        assert!(err.message.contains("MSP profiles only"), "{err}");
    }
}
