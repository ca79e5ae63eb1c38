//! The motion tab: angle (slider or typed, with an interval: ROTATE; or multi-turn, with
//! acceleration and deceleration: ROTATE_MTURN_BY_INTERVAL), a live angle readout and
//! plot (READ_ANGLE polled; MONITOR too where the servo answers it), wheel mode (stop,
//! continuous, turns, timed; direction), damping with a holding power.
//!
//! Motion commands go straight to the link worker: they never wait behind a job, and the live
//! angle keeps coming while the servo moves.

use super::selection_or_hint;
use super::{Servo, direct, error_label, follow};
use crate::i18n::Lang;
use crate::link::{LinkCommand, Poll};
use crate::ops::FieldValues;
use crate::ops::OpError;
use crate::ops::servo::{self as ops, Wheel};
use crate::profile::{Field, Value};
use crate::protocol::servo::cmd;
use crate::ui::Action;
use crate::ui::station::{Notice, Reading, Station};
use crate::ui::zh::Zh;
use eframe::egui;
use egui_plot::{Line, Plot, PlotPoints};
use std::time::{Duration, Instant};

/// The most angle samples kept for the plot.
const MAX_POINTS: usize = 4000;

/// The wheel-mode methods offered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WheelMode {
    /// Stop turning.
    #[default]
    Stop,
    /// Turn until stopped.
    Continuous,
    /// A number of turns.
    Turns,
    /// A number of milliseconds.
    Timed,
}

impl WheelMode {
    const ALL: [WheelMode; 4] = [
        WheelMode::Stop,
        WheelMode::Continuous,
        WheelMode::Turns,
        WheelMode::Timed,
    ];

    fn name(self, lang: Lang) -> &'static str {
        match self {
            WheelMode::Stop => lang.tr("Stop", "停止"),
            WheelMode::Continuous => lang.tr("Continuous", "持续旋转"),
            WheelMode::Turns => lang.tr("Turns", "定圈"),
            WheelMode::Timed => lang.tr("Timed", "定时"),
        }
    }
}

/// The motion tab's state.
pub struct MotionState {
    /// The slider's angle, degrees.
    pub angle: f64,
    /// The angle as typed, degrees.
    pub angle_text: String,
    /// The interval as typed, ms.
    pub interval: String,
    /// The power as typed, mW (0: the servo's limit).
    pub power: String,
    /// A multi-turn move (ROTATE_MTURN_BY_INTERVAL), with its acceleration and deceleration.
    pub multi_turn: bool,
    /// Multi-turn: acceleration time as typed, ms.
    pub t_acc: String,
    /// Multi-turn: deceleration time as typed, ms.
    pub t_dec: String,
    /// READ_ANGLE is polled.
    pub live: bool,
    /// MONITOR is polled too.
    pub monitor: bool,
    /// Angle samples: seconds since `t0`, degrees.
    pub series: Vec<[f64; 2]>,
    last_at: Option<Instant>,
    t0: Instant,
    /// The wheel-mode method.
    pub wheel: WheelMode,
    /// Clockwise.
    pub clockwise: bool,
    /// Wheel speed as typed, °/s.
    pub speed: String,
    /// Turns or milliseconds as typed.
    pub value: String,
    /// Damping holding power as typed, mW.
    pub damping: String,
}

impl Default for MotionState {
    fn default() -> Self {
        Self {
            angle: 0.0,
            angle_text: "0.0".into(),
            interval: "500".into(),
            power: "0".into(),
            multi_turn: false,
            t_acc: "20".into(),
            t_dec: "20".into(),
            live: false,
            monitor: false,
            series: Vec::new(),
            last_at: None,
            t0: Instant::now(),
            wheel: WheelMode::Stop,
            clockwise: true,
            speed: "60".into(),
            value: "3".into(),
            damping: "0".into(),
        }
    }
}

/// A command's request field by ident.
fn field<'p>(rt: &'p Station, command: u8, ident: &str) -> Option<&'p Field> {
    rt.device
        .profile
        .command_by_id(command)?
        .request
        .iter()
        .find(|f| f.ident == ident)
}

/// What a person typed for a command's field, as a raw value, or why it does not fit.
fn raw(rt: &Station, command: u8, ident: &str, text: &str) -> Result<i64, OpError> {
    let f = field(rt, command, ident)
        .ok_or_else(|| OpError::unknown_param(&rt.device.profile, ident))?;
    match f.parse(text)? {
        Value::Int(v) => Ok(v),
        _ => Err(crate::profile::FieldError::WrongType {
            field: ident.to_string(),
            expected: "a number".into(),
        }
        .into()),
    }
}

/// A labelled text entry that turns red when `ok` is false.
fn entry(ui: &mut egui::Ui, label: &str, text: &mut String, ok: bool) -> egui::Response {
    // The label and its box move to the next row together.
    crate::ui::layout::group(ui, label, |ui| {
        let l = ui.label(label);
        let mut edit = egui::TextEdit::singleline(text).desired_width(60.0);
        if !ok {
            edit = edit.text_color(egui::Color32::from_rgb(210, 40, 40));
        }
        ui.add(edit).labelled_by(l.id)
    })
}

impl MotionState {
    /// Forgets the plotted angle (another servo).
    pub fn clear_plot(&mut self) {
        self.series.clear();
        self.last_at = None;
        self.t0 = Instant::now();
    }

    fn polls(&self, id: u8) -> Vec<Poll> {
        let mut polls = vec![Poll {
            request: ops::read_angle_request(id),
            interval: Some(Duration::from_millis(50)),
        }];
        if self.monitor {
            polls.push(Poll {
                request: ops::monitor_request(id),
                interval: Some(Duration::from_millis(250)),
            });
        }
        polls
    }

    /// Takes a new READ_ANGLE answer of `id` into the plot.
    fn collect(&mut self, rt: &Station, id: u8) {
        let Some(Reading::Values(values, at)) = rt.device.readings.get(&cmd::READ_ANGLE) else {
            return;
        };
        if self.last_at == Some(*at) {
            return;
        }
        self.last_at = Some(*at);
        if let (Some(sid), Some(a)) = (values.int("servo_id"), values.int("angle"))
            && sid == i64::from(id)
        {
            let t = at.saturating_duration_since(self.t0).as_secs_f64();
            self.series.push([t, a as f64 * 0.1]);
            if self.series.len() > MAX_POINTS {
                self.series.drain(..self.series.len() - MAX_POINTS);
            }
        }
    }

    /// Draws the tab.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        busy: bool,
        selected: Option<Servo>,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        let Some(servo) = selection_or_hint(ui, lang, selected) else {
            return actions;
        };
        let can = rt.connected() && !busy;
        if busy {
            ui.weak(lang.tr(
                "A job is running: motion commands wait until it ends. STOP ALL always works.",
                "有任务在运行: 运动指令需等待任务结束。全部停止始终可用。",
            ));
        }
        actions.extend(self.angle_section(ui, lang, rt, servo, can));
        actions.extend(self.live_section(ui, lang, rt, servo, can));
        actions.extend(self.wheel_section(ui, lang, rt, servo, can));
        actions.extend(self.damping_section(ui, lang, rt, servo, can));
        actions
    }

    /// Go to an angle: typed or on the slider, with its interval and power; a multi-turn move
    /// with its acceleration and deceleration, refused as typed when its interval is shorter
    /// than the profile allows (the same check as `servo angle --multi-turn`).
    fn angle_section(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.heading(lang.tr("Angle", "角度"));
        let command = self.angle_command();
        let angle = raw(rt, command, "angle", &self.angle_text);
        let interval = raw(rt, command, "interval", &self.interval);
        let power = raw(rt, command, "power", &self.power);
        let request = self.angle_request(rt, servo.id, [&angle, &interval, &power]);
        crate::ui::layout::toolbar(ui, |ui| {
            self.angle_inputs(ui, lang, [&angle, &interval, &power]);
            if ui
                .add_enabled(
                    can && request.is_ok(),
                    egui::Button::new(lang.tr("Go to angle", "转到角度")),
                )
                .clicked()
            {
                send(&mut actions, rt, servo, request.clone());
            }
        });
        let typed = [&angle, &interval, &power];
        let first = typed.into_iter().find_map(|r| r.as_ref().err());
        if let Some(e) = first.or(request.as_ref().err()) {
            error_label(ui, e.in_lang(lang));
        }
        actions
    }

    /// ROTATE, or ROTATE_MTURN_BY_INTERVAL for a multi-turn move.
    fn angle_command(&self) -> u8 {
        if self.multi_turn {
            cmd::ROTATE_MTURN_BY_INTERVAL
        } else {
            cmd::ROTATE
        }
    }

    /// The request "Go to angle" sends, checked against the profile (its ranges and, for a
    /// multi-turn move, the interval's relation to t_acc + t_dec), or why it cannot be sent.
    fn angle_request(
        &self,
        rt: &Station,
        id: u8,
        [angle, interval, power]: [&Result<i64, OpError>; 3],
    ) -> Result<crate::link::Request, OpError> {
        let (a, i, p) = (angle.clone()?, interval.clone()?, power.clone()?);
        let profile = &rt.device.profile;
        if !self.multi_turn {
            return ops::rotate_request(profile, id, a, i, p);
        }
        let t_acc_ms = raw(rt, cmd::ROTATE_MTURN_BY_INTERVAL, "t_acc", &self.t_acc)?;
        let t_dec_ms = raw(rt, cmd::ROTATE_MTURN_BY_INTERVAL, "t_dec", &self.t_dec)?;
        let turn = ops::MultiTurn {
            deci_degrees: a,
            interval_ms: i,
            t_acc_ms,
            t_dec_ms,
            power: p,
        };
        ops::multi_turn_request(profile, id, turn)
    }

    /// The slider (single turn), the typed angle, interval and power, the multi-turn checkbox
    /// and its acceleration and deceleration.
    fn angle_inputs(&mut self, ui: &mut egui::Ui, lang: Lang, ok: [&Result<i64, OpError>; 3]) {
        let [angle, interval, power] = ok.map(Result::is_ok);
        ui.checkbox(&mut self.multi_turn, lang.tr("Multi-turn", "多圈"));
        if !self.multi_turn {
            let l = ui.label(lang.tr("Target angle", "目标角度"));
            let slider = egui::Slider::new(&mut self.angle, -180.0..=180.0)
                .step_by(0.1)
                .suffix("°");
            if ui.add(slider).labelled_by(l.id).changed() {
                self.angle_text = format!("{:.1}", self.angle);
            }
        }
        let typed = entry(ui, lang.tr("Angle (°)", "角度(°)"), &mut self.angle_text, angle);
        if !self.multi_turn
            && typed.changed()
            && let Ok(v) = self.angle_text.trim().parse::<f64>()
        {
            self.angle = v.clamp(-180.0, 180.0);
        }
        entry(ui, lang.tr("Interval (ms)", "时间(ms)"), &mut self.interval, interval);
        if self.multi_turn {
            entry(ui, lang.tr("Acceleration (ms)", "加速时间(ms)"), &mut self.t_acc, true);
            entry(ui, lang.tr("Deceleration (ms)", "减速时间(ms)"), &mut self.t_dec, true);
        }
        let power_label = lang.tr("Power (mW, 0 = limit)", "功率(mW, 0为上限)");
        entry(ui, power_label, &mut self.power, power);
    }

    /// The live angle (and monitor) polled, its readout and plot.
    fn live_section(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.horizontal(|ui| {
            // Not while a job runs: polling takes the port to the servo's rate.
            let live = ui.add_enabled(
                can,
                egui::Checkbox::new(&mut self.live, lang.tr("Live angle", "实时角度")),
            );
            let monitor = ui.add_enabled(
                can,
                egui::Checkbox::new(
                    &mut self.monitor,
                    lang.tr("Also monitor (newer servos)", "同时监控(新款舵机)"),
                ),
            );
            if live.changed() || (monitor.changed() && self.live) {
                if self.live {
                    actions.extend(follow(rt, servo.baud));
                    actions.push(Action::Link(LinkCommand::SetPolls(self.polls(servo.id))));
                } else {
                    actions.push(Action::Link(LinkCommand::SetPolls(Vec::new())));
                }
            }
            if ui.button(lang.tr("Clear plot", "清除曲线")).clicked() {
                self.clear_plot();
            }
        });
        if self.live {
            self.collect(rt, servo.id);
            ui.ctx().request_repaint_after(crate::ui::repaint::LIVE);
        }
        self.readout(ui, lang, rt, servo);
        Plot::new("servo-angle")
            .height(180.0)
            .x_axis_label(lang.tr("time (s)", "时间 (s)"))
            .y_axis_label(lang.tr("angle (°)", "角度 (°)"))
            .allow_scroll(false)
            .show(ui, |p| {
                p.line(Line::new(
                    lang.tr("angle (°)", "角度(°)"),
                    PlotPoints::from(self.series.clone()),
                ));
            });

        actions
    }

    /// Wheel mode: stop, continuous, a number of turns or a time, at a speed and direction.
    fn wheel_section(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.heading(lang.tr("Wheel mode", "轮式模式"));
        let speed = raw(rt, cmd::SPIN, "speed", &self.speed);
        let needs_value = matches!(self.wheel, WheelMode::Turns | WheelMode::Timed);
        let value = raw(rt, cmd::SPIN, "value", &self.value);
        crate::ui::layout::toolbar(ui, |ui| {
            let l = ui.label(lang.tr("Method", "方式"));
            egui::ComboBox::from_id_salt("servo-wheel")
                .selected_text(self.wheel.name(lang))
                .show_ui(ui, |ui| {
                    for m in WheelMode::ALL {
                        ui.selectable_value(&mut self.wheel, m, m.name(lang));
                    }
                })
                .response
                .labelled_by(l.id);
            ui.checkbox(&mut self.clockwise, lang.tr("Clockwise", "顺时针"));
            entry(
                ui,
                lang.tr("Speed (°/s)", "速度(°/s)"),
                &mut self.speed,
                speed.is_ok(),
            );
            let what = match self.wheel {
                WheelMode::Timed => lang.tr("Time (ms)", "时间(ms)"),
                _ => lang.tr("Turns", "圈数"),
            };
            if needs_value {
                entry(ui, what, &mut self.value, value.is_ok());
            }
            let ok = speed.is_ok() && (!needs_value || value.is_ok());
            if ui
                .add_enabled(
                    can && ok,
                    egui::Button::new(lang.tr("Run wheel", "执行轮式")),
                )
                .clicked()
                && let Ok(s) = &speed
            {
                let v = value.as_ref().ok().map_or(0, |v| *v as u16);
                let wheel = match self.wheel {
                    WheelMode::Stop => Wheel::Stop,
                    WheelMode::Continuous => Wheel::Continuous,
                    WheelMode::Turns => Wheel::Turns(v),
                    WheelMode::Timed => Wheel::Timed(v),
                };
                send(
                    &mut actions,
                    rt,
                    servo,
                    ops::spin_request(
                        &rt.device.profile,
                        servo.id,
                        wheel,
                        self.clockwise,
                        *s as u16,
                    ),
                );
            }
        });
        for e in [&speed]
            .into_iter()
            .chain(needs_value.then_some(&value))
            .filter_map(|r| r.as_ref().err())
        {
            error_label(ui, e.in_lang(lang));
        }

        actions
    }

    /// Damping mode, with its holding power.
    fn damping_section(
        &mut self,
        ui: &mut egui::Ui,
        lang: Lang,
        rt: &Station,
        servo: Servo,
        can: bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        ui.heading(lang.tr("Damping", "阻尼"));
        let damping = raw(rt, cmd::DAMPING, "power", &self.damping);
        ui.horizontal(|ui| {
            entry(
                ui,
                lang.tr("Holding power (mW, 0 = limit)", "保持功率(mW, 0为上限)"),
                &mut self.damping,
                damping.is_ok(),
            );
            if ui
                .add_enabled(
                    can && damping.is_ok(),
                    egui::Button::new(lang.tr("Damping mode", "进入阻尼模式")),
                )
                .clicked()
                && let Ok(p) = &damping
            {
                send(
                    &mut actions,
                    rt,
                    servo,
                    ops::damping_request(&rt.device.profile, servo.id, *p),
                );
            }
            if let Err(e) = &damping {
                error_label(ui, e.in_lang(lang));
            }
        });
        actions
    }

    /// The latest angle and monitor values of the selected servo, nothing before they arrive.
    fn readout(&self, ui: &mut egui::Ui, lang: Lang, rt: &Station, servo: Servo) {
        let of_servo = |values: &FieldValues| values.int("servo_id") == Some(servo.id.into());
        ui.horizontal(|ui| {
            ui.label(lang.tr("Angle now:", "当前角度:"));
            match rt.device.readings.get(&cmd::READ_ANGLE) {
                Some(Reading::Values(values, at)) if of_servo(values) && self.live => {
                    if let Some(a) = values.int("angle") {
                        ui.label(
                            egui::RichText::new(format!("{:.1}°", a as f64 * 0.1))
                                .size(20.0)
                                .strong(),
                        );
                        ui.weak(format!(
                            "{} ms {}",
                            at.elapsed().as_millis(),
                            lang.tr("ago", "前")
                        ));
                    }
                }
                Some(Reading::Failed(e)) if self.live => error_label(ui, e.in_lang(lang)),
                _ => {
                    ui.weak(lang.tr("turn on Live angle", "请开启实时角度"));
                }
            }
        });
        if !(self.live && self.monitor) {
            return;
        }
        match rt.device.readings.get(&cmd::MONITOR) {
            Some(Reading::Values(values, _)) if of_servo(values) && monitor_no_data(values) => {
                ui.weak(lang.tr(
                    "monitor: no data (the servo has no reading to give)",
                    "监控:无数据(舵机暂无读数)",
                ));
            }
            Some(Reading::Values(values, _)) if of_servo(values) => {
                let Some(mon) = rt.device.profile.command_by_id(cmd::MONITOR) else {
                    return;
                };
                crate::ui::layout::toolbar(ui, |ui| {
                    for f in mon.reply.iter().skip(1) {
                        if let Some(v) = values.get(&f.ident) {
                            let shown = if f.ident == "status" {
                                match v {
                                    Value::Int(s) => format!("{s:#04x}"),
                                    _ => f.format(v),
                                }
                            } else {
                                crate::ui::inputs::said_in(f.display(v), lang)
                            };
                            ui.label(format!("{}: {shown}", lang.tr(&f.name.en, &f.name.zh)));
                            ui.separator();
                        }
                    }
                });
            }
            Some(Reading::Failed(e)) => error_label(
                ui,
                format!(
                    "{}: {e}",
                    lang.tr(
                        "monitor: no answer (older servos do not answer it)",
                        "监控无应答(旧款舵机不支持)"
                    )
                ),
            ),
            _ => {}
        }
    }
}

/// Sends `request` to the selected servo (the port following its rate first), or says why it
/// was refused.
fn send(
    actions: &mut Vec<Action>,
    rt: &Station,
    servo: Servo,
    request: Result<crate::link::Request, OpError>,
) {
    match request {
        Ok(r) => {
            actions.extend(follow(rt, servo.baud));
            actions.push(direct(r));
        }
        Err(e) => actions.push(Action::Notify(Notice::error(e.said()))),
    }
}

/// Whether a MONITOR answer is the "no data" form (angle -235929599, turns 0): shown as no
/// data, not as an angle of -23592959.9°.
fn monitor_no_data(values: &FieldValues) -> bool {
    match (values.int("angle"), values.int("turns")) {
        (Some(a), Some(t)) => crate::ops::servo::monitor::is_no_data(a, t),
        _ => false,
    }
}
