//! The engineer's unlock of the station window: the operator view is locked; an engineer types
//! the password whose SHA-256 the bundle holds (`engineer_password_sha256`) and sees each slot's
//! configuration (port, profile, plan and its steps), and may open any idle slot in the
//! engineer view ([`super::lent`]), until locking again. Each unlock, refused password and lock
//! is returned as an [`Access`] for the station to record
//! ([`crate::ops::station::access`]).

use crate::ops::station::Access;
use eframe::egui;

/// The lock's state.
#[derive(Debug, Clone, Default)]
pub struct Engineer {
    /// The SHA-256 the password must have; `None`: the bundle names none, nobody unlocks.
    pub password_sha256: Option<String>,
    /// The password field, while asking.
    pub typed: String,
    /// Whether the password field is shown.
    pub asking: bool,
    /// When it was unlocked (local `HH:MM:SS`); `None` while locked.
    pub unlocked_at: Option<String>,
    /// What the last try said (a wrong password, no password in the bundle).
    pub said: Option<(String, String)>,
}

impl Engineer {
    /// Whether the engineer view is open.
    pub fn unlocked(&self) -> bool {
        self.unlocked_at.is_some()
    }

    /// Tries `typed` as the engineer's password: [`Access::Unlock`], or [`Access::Refused`]
    /// (a wrong password, or none in the bundle).
    pub fn try_unlock(&mut self) -> Access {
        let typed = std::mem::take(&mut self.typed);
        let Some(want) = &self.password_sha256 else {
            self.said = Some((
                "the bundle holds no engineer password".into(),
                "配置包未设置工程师密码".into(),
            ));
            return Access::Refused {
                why: "the bundle holds no engineer password".into(),
            };
        };
        let got = crate::ops::records::record::sha256_hex(typed.as_bytes());
        if &got == want {
            self.unlocked_at = Some(chrono::Local::now().format("%H:%M:%S").to_string());
            self.asking = false;
            self.said = None;
            Access::Unlock
        } else {
            self.said = Some(("wrong password".into(), "密码错误".into()));
            Access::Refused {
                why: "wrong password".into(),
            }
        }
    }

    /// The title bar's part: the unlock button and field, or the lock button. Returns an
    /// unlock, a refused password or a lock, when one happened.
    pub fn show(&mut self, ui: &mut egui::Ui, zh: bool) -> Option<Access> {
        if let Some(at) = &self.unlocked_at {
            ui.label(if zh {
                format!("工程师视图(自 {at})")
            } else {
                format!("engineer view (since {at})")
            });
            if ui.button(if zh { "锁定" } else { "Lock" }).clicked() {
                self.unlocked_at = None;
                return Some(Access::Lock);
            }
            return None;
        }
        if !self.asking {
            if ui
                .button(if zh {
                    "工程师解锁"
                } else {
                    "Engineer unlock"
                })
                .clicked()
            {
                self.asking = true;
            }
            return None;
        }
        let field = ui.add(
            egui::TextEdit::singleline(&mut self.typed)
                .password(true)
                .hint_text(if zh { "密码" } else { "password" })
                .desired_width(140.0),
        );
        let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        let mut tried = None;
        if ui.button(if zh { "解锁" } else { "Unlock" }).clicked() || entered {
            tried = Some(self.try_unlock());
        }
        if let Some((en, zh_text)) = &self.said {
            ui.colored_label(
                egui::Color32::from_rgb(200, 30, 30),
                if zh { zh_text } else { en },
            );
        }
        tried
    }
}
