//! The engineer's unlock of the station window: the operator view is locked; an engineer types
//! the password whose SHA-256 the bundle holds (`engineer_password_sha256`) and sees each slot's
//! configuration (port, profile, plan and its steps) until locking again. Each unlock and each
//! refused password is logged (`log::warn`, shown with `RUST_LOG=botbench=warn`) with the time.

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

    /// Tries `typed` as the password of station `id`.
    pub fn try_unlock(&mut self, id: &str) {
        let typed = std::mem::take(&mut self.typed);
        let Some(want) = &self.password_sha256 else {
            self.said = Some((
                "the bundle holds no engineer password".into(),
                "配置包未设置工程师密码".into(),
            ));
            return;
        };
        let got = crate::ops::records::record::sha256_hex(typed.as_bytes());
        let now = chrono::Local::now().format("%H:%M:%S").to_string();
        if &got == want {
            log::warn!("station {id}: engineer view unlocked at {now}");
            self.unlocked_at = Some(now);
            self.asking = false;
            self.said = None;
        } else {
            log::warn!("station {id}: wrong engineer password at {now}");
            self.said = Some(("wrong password".into(), "密码错误".into()));
        }
    }

    /// The title bar's part: the unlock button and field, or the lock button.
    pub fn show(&mut self, ui: &mut egui::Ui, id: &str, zh: bool) {
        if let Some(at) = &self.unlocked_at {
            ui.label(if zh {
                format!("工程师视图(自 {at})")
            } else {
                format!("engineer view (since {at})")
            });
            if ui.button(if zh { "锁定" } else { "Lock" }).clicked() {
                self.unlocked_at = None;
            }
            return;
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
            return;
        }
        let field = ui.add(
            egui::TextEdit::singleline(&mut self.typed)
                .password(true)
                .hint_text(if zh { "密码" } else { "password" })
                .desired_width(140.0),
        );
        let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if ui.button(if zh { "解锁" } else { "Unlock" }).clicked() || entered {
            self.try_unlock(id);
        }
        if let Some((en, zh_text)) = &self.said {
            ui.colored_label(
                egui::Color32::from_rgb(200, 30, 30),
                if zh { zh_text } else { en },
            );
        }
    }
}
