//! The packet monitor: every frame sent and received, with time, direction, hex and decoded
//! meaning (command name, fields, errors), and each request's attempt that went unanswered as a
//! row of its own. Filter by command, pause, copy, save as text to a typed or chosen file.
//!
//! Each frame is decoded with the profile it came under: after a change of device, the earlier
//! frames keep their commands' names, marked with their profile's id.
//!
//! The view follows the newest frame unless the technician scrolls away; then it stays on the
//! frames they scrolled to (held by sequence number, so that frames dropped from the front of a
//! full log or arriving at the end do not move it), says how far behind the newest it is, and
//! follows again from the bottom or with "Newest".

use super::Action;
use super::files;
use super::settings::FileKind;
use super::station::{Notice, Station};
use crate::i18n::Lang;
use crate::i18n::Text;
use crate::link::{LogEntry, NoAnswer};
use crate::profile::Profile;
use crate::protocol::{Direction, hex};
use crate::ui::zh::Zh;
use eframe::egui;

/// The monitor's view state.
pub struct MonitorPanel {
    /// Show only frames whose command name or number contains this.
    pub filter: String,
    /// Show errors only.
    pub errors_only: bool,
    /// Keep the newest frame in view.
    pub follow: bool,
    /// While not following: the frame at the top of the view (its sequence number), and how
    /// far into its row the view starts.
    anchor: Option<(u64, f32)>,
    /// The offset the view was put at last frame, to tell the technician's scrolling from it.
    placed: Option<f32>,
    /// The height of the rows' view last frame.
    view_h: Option<f32>,
    /// The frame at the top of the view when last drawn.
    pub top: Option<u64>,
    /// While not following: frames shown below the view, and how many seconds the last one in
    /// view is older than the newest.
    pub behind: Option<(usize, f64)>,
    /// The file the log is saved to.
    pub save_path: String,
    /// The capture file recorded to or opened.
    pub capture_path: String,
}

impl Default for MonitorPanel {
    fn default() -> Self {
        Self {
            filter: String::new(),
            errors_only: false,
            follow: true,
            anchor: None,
            placed: None,
            view_h: None,
            top: None,
            behind: None,
            save_path: String::new(),
            capture_path: String::new(),
        }
    }
}

/// What a row shows: a frame (live or from a capture file), or an attempt unanswered.
#[derive(Debug, Clone, Copy)]
pub enum Shown<'a> {
    /// A frame sent or received, or a damaged one.
    Frame(&'a LogEntry),
    /// A request's attempt that no frame answered.
    NoAnswer(&'a NoAnswer),
}

impl Shown<'_> {
    /// When it happened.
    fn at(&self) -> std::time::SystemTime {
        match self {
            Shown::Frame(e) => e.at,
            Shown::NoAnswer(n) => n.at,
        }
    }
}

impl<'a> From<&'a super::station::LogRow> for Shown<'a> {
    fn from(row: &'a super::station::LogRow) -> Self {
        match row {
            super::station::LogRow::Frame(e) => Shown::Frame(e),
            super::station::LogRow::NoAnswer(n) => Shown::NoAnswer(n),
        }
    }
}

/// A row to show: its sequence number, the profile it is decoded with, what it shows.
type Row<'a> = (u64, &'a Profile, Shown<'a>);

/// An unanswered attempt in words: `no answer to MSP_GET_PWMVALUE (0x82) after 25 ms, attempt
/// 1 of 3`, the command named by `profile`.
pub fn no_answer_said(profile: &Profile, n: &NoAnswer) -> Text {
    let name = profile
        .command_by_id(n.command)
        .map_or_else(|| format!("command {}", n.command), |c| c.ident.clone());
    let ms = n.waited.as_millis();
    let (k, m) = (n.attempt, n.attempts);
    let said = Text::new(
        format!("no answer to {name} ({:#04x}) after {ms} ms, attempt {k} of {m}", n.command),
        format!("{name} ({:#04x}) 无应答,已等待 {ms} ms,第 {k}/{m} 次尝试", n.command),
    );
    match n.host_late {
        Some(late) => said.then("; ", &crate::link::request::held_up_said(late)),
        None => said,
    }
}

/// One log line, in `lang`: `12:00:01.234 >> ff ff 03 82 00 81  MSP_GET_PWMVALUE`, decoded
/// with `profile`; an unanswered attempt `12:00:01.260 ?? … no answer to MSP_GET_PWMVALUE
/// (0x82) after 25 ms, attempt 1 of 3`. A row of another profile than `current` (the device in
/// use now) is marked with its profile's id: `[window-cleaner] 12:00:01.234 >> …`.
pub fn line(lang: Lang, current: &Profile, profile: &Profile, row: Shown<'_>) -> String {
    let time = chrono::DateTime::<chrono::Local>::from(row.at()).format("%H:%M:%S%.3f");
    let time = if profile.id == current.id {
        time.to_string()
    } else {
        format!("[{}] {time}", profile.id)
    };
    let e = match row {
        Shown::Frame(e) => e,
        Shown::NoAnswer(n) => {
            return format!("{time} ?? {:<40} {}", "", no_answer_said(profile, n).get(lang));
        }
    };
    match &e.frame {
        Ok(p) => format!(
            "{time} {} {:<40} {}{}",
            e.direction.arrow(),
            hex::format(&p.wire),
            p.summary(profile),
            e.note
                .as_ref()
                .map_or(String::new(), |n| format!("  [{n}]"))
        ),
        Err(err) => format!(
            "{time} {} {:<40} !! {err}",
            e.direction.arrow(),
            hex::format(err.bytes())
        ),
    }
}

/// [`line`] as the window shows it in `lang`: in 中文 a frame's values, its misfit and its
/// marks are said in Chinese (the wire names and numbers stay; a saved or copied log is
/// [`line`], in English).
pub fn line_in(current: &Profile, profile: &Profile, row: Shown<'_>, lang: Lang) -> String {
    let english = line(lang, current, profile, row);
    let (Lang::Zh, Shown::Frame(LogEntry { frame: Ok(p), .. })) = (lang, row) else {
        return english;
    };
    let (Some(cmd), Some(d)) = (p.command_in(profile), p.decode_lenient(profile)) else {
        return english;
    };
    let mut s = cmd.ident.clone();
    if let crate::packet::Header::MspReply {
        kind: crate::protocol::msp::ReplyKind::Async,
    } = p.header
    {
        s.push_str("(主动上报,类型 0xFE:不应答任何请求)");
    }
    for v in &d.values {
        s.push_str(&format!(" {}={}", v.ident, crate::ui::zh::value_marks(&v.display(), Lang::Zh)));
    }
    if let Some(m) = d.misfit() {
        let mut misfit = crate::profile::FieldError::Misfit(Box::new(m)).zh();
        // A data point by its name in the profile, not its code.
        for dp in &profile.data_points {
            let code = format!("数据点 {}:", dp.field.ident);
            misfit = misfit.replace(&code, &format!("数据点 {}:", dp.field.name.zh));
        }
        s.push_str(&format!(" !{misfit} [{}]", hex::format(&p.payload)));
    }
    let summary = p.summary(profile);
    match english.find(&summary) {
        Some(at) => format!("{}{s}{}", &english[..at], &english[at + summary.len()..]),
        None => english,
    }
}

impl MonitorPanel {
    /// The capture file row: its path (typed, or chosen with Browse…: opened at once), Record /
    /// Stop recording with the file's size growing, Open capture / Back to live.
    fn capture_bar(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let recording = rt.recording();
        let event = files::row(
            ui,
            lang,
            files::Row {
                label: lang.tr("Capture", "抓包文件"),
                hint: "capture.pcapng",
                pick: files::Pick::Open(&["pcapng"]),
                enabled: recording.is_none(),
            },
            &mut self.capture_path,
            &rt.dialogs,
        );
        let path = self.capture_path.trim().to_string();
        match recording {
            Some(c) => {
                if ui.button(lang.tr("Stop recording", "停止录制")).clicked() {
                    actions.push(Action::StopCapture);
                }
                let lost = if c.dropped() > 0 {
                    format!(", {} {}", c.dropped(), lang.tr("chunks lost", "块丢失"))
                } else {
                    String::new()
                };
                ui.colored_label(
                    egui::Color32::RED,
                    format!(
                        "{} {}  {:.1} KiB{lost}",
                        lang.tr("REC", "录制中"),
                        c.path(),
                        c.file_bytes() as f64 / 1024.0
                    ),
                );
                ui.ctx()
                    .request_repaint_after(std::time::Duration::from_millis(250));
            }
            None => {
                let record = ui
                    .add_enabled(rt.connected(), egui::Button::new(lang.tr("Record", "录制")))
                    .on_hover_text(lang.tr(
                        "record the port's bytes to a new pcapng capture at the path typed \
                         (Wireshark, botbench sim replay)",
                        "将端口字节录制到所填路径的新 pcapng 抓包文件(Wireshark、botbench sim replay)",
                    ));
                if record.clicked() {
                    match record_to(&path) {
                        Ok(p) => {
                            actions.push(Action::RememberFile(FileKind::Capture, path.clone()));
                            actions.push(Action::StartCapture(p));
                        }
                        Err(n) => actions.push(Action::Notify(n)),
                    }
                }
            }
        }
        match &rt.packets.offline {
            Some(o) => {
                ui.label(format!(
                    "{} {}{}",
                    lang.tr("viewing", "查看"),
                    o.name,
                    o.truncated
                        .as_ref()
                        .map_or(String::new(), |t| format!(" (cut off: {t})"))
                ));
                if ui.button(lang.tr("Back to live", "返回实时")).clicked() {
                    actions.push(Action::CloseCapture);
                }
            }
            None => {
                let open = ui
                    .add_enabled(
                        !path.is_empty(),
                        egui::Button::new(lang.tr("Open capture", "打开抓包")),
                    )
                    .clicked();
                if event.go(open, &mut actions) {
                    actions.push(Action::RememberFile(FileKind::Capture, path.clone()));
                    actions.push(Action::OpenCapture(path.into()));
                }
            }
        }
        actions
    }

    /// Whether a row passes the filter and the errors-only switch (an unanswered attempt
    /// counts as an error, and is filtered by its request's command).
    fn matches(&self, profile: &Profile, row: Shown<'_>) -> bool {
        let command = match row {
            Shown::Frame(e) if self.errors_only && e.frame.is_ok() => return false,
            Shown::Frame(e) => e.frame.as_ref().ok().map(|p| p.command),
            Shown::NoAnswer(n) => Some(n.command),
        };
        let f = self.filter.trim();
        if f.is_empty() {
            return true;
        }
        match command {
            Some(id) => {
                let name = profile.command_by_id(id).map_or("", |c| c.ident.as_str());
                command_matches(f, id, name)
            }
            None => false,
        }
    }

    /// Draws the panel.
    fn draw(&mut self, ui: &mut egui::Ui, lang: Lang, rt: &Station) -> Vec<Action> {
        let mut actions = Vec::new();
        let log = &rt.packets;
        // A capture opened offline is shown in place of the live log, decoded with its profile;
        // the live log's frames each with the profile they came under.
        let (profile, entries_len, rows): (_, usize, Vec<Row<'_>>) = match &log.offline {
            Some(o) => (
                o.profile.clone(),
                o.entries.len(),
                (0u64..)
                    .zip(o.entries.iter())
                    .map(|(s, e)| (s, &*o.profile, Shown::Frame(e)))
                    .filter(|(_, p, e)| self.matches(p, *e))
                    .collect(),
            ),
            None => (
                rt.device.profile.clone(),
                log.entries.len(),
                log.numbered()
                    .map(|(s, l)| (s, &*l.profile, Shown::from(&l.row)))
                    .filter(|(_, p, e)| self.matches(p, *e))
                    .collect(),
            ),
        };
        crate::ui::layout::toolbar(ui, |ui| actions.extend(self.capture_bar(ui, lang, rt)));
        crate::ui::layout::toolbar(ui, |ui| {
            let label = ui.label(lang.tr("Filter", "筛选"));
            ui.add(
                egui::TextEdit::singleline(&mut self.filter)
                    .hint_text(lang.tr("command name or number", "命令名或编号"))
                    .desired_width(180.0),
            )
            .labelled_by(label.id);
            ui.checkbox(&mut self.errors_only, lang.tr("errors only", "仅错误"));
            let pause = if log.paused {
                lang.tr("Resume", "继续")
            } else {
                lang.tr("Pause", "暂停")
            };
            if ui.add(super::inputs::steady_button(pause)).clicked() {
                actions.push(Action::PausePacketLog(!log.paused));
            }
            if ui.button(lang.tr("Clear", "清空")).clicked() {
                actions.push(Action::ClearPacketLog);
            }
            if ui.button(lang.tr("Copy", "复制")).clicked() {
                let shown: Vec<String> = rows
                    .iter()
                    .map(|(_, p, e)| line(lang, &profile, p, *e))
                    .collect();
                ui.ctx().copy_text(shown.join("\n"));
                actions.push(Action::Notify(Notice::info(Text::new(
                    format!("{} line(s) copied", shown.len()),
                    format!("已复制 {} 行", shown.len()),
                ))));
            }
            ui.weak(format!(
                "{} {} / {}{}",
                rows.len(),
                lang.tr("shown", "条显示"),
                entries_len,
                if log.dropped > 0 {
                    format!(
                        ", {} {}",
                        log.dropped,
                        lang.tr("not kept while paused", "暂停期间未记录")
                    )
                } else {
                    String::new()
                }
            ));
        });
        crate::ui::layout::toolbar(ui, |ui| {
            let event = files::row(
                ui,
                lang,
                files::Row {
                    label: lang.tr("File", "文件"),
                    hint: "packets.txt",
                    pick: files::Pick::Save("packets.txt"),
                    enabled: true,
                },
                &mut self.save_path,
                &rt.dialogs,
            );
            let save = ui.button(lang.tr("Save", "保存")).clicked();
            if event.go(save, &mut actions) {
                let port = rt.link.target().map(super::station::Target::label);
                actions.extend(self.save(lang, &profile, &rows, port.as_deref()));
            }
        });
        self.where_the_view_is(ui, lang);
        ui.separator();
        self.rows(ui, lang, &profile, &rows);
        actions
    }

    /// Following, or how far behind the newest the view is, with a way back.
    fn where_the_view_is(&mut self, ui: &mut egui::Ui, lang: Lang) {
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.follow, lang.tr("Follow the newest", "跟随最新"));
            if let (false, Some((below, secs))) = (self.follow, self.behind) {
                ui.colored_label(
                    egui::Color32::from_rgb(220, 150, 0),
                    format!(
                        "{below} {} ({secs:.1} s {})",
                        lang.tr("newer frame(s) below the view", "条更新的帧在下方"),
                        lang.tr("behind the newest", "落后于最新")
                    ),
                );
                if ui.button(lang.tr("Newest", "最新")).clicked() {
                    self.follow = true;
                }
            }
        });
    }

    /// The rows, in a scroll area with a solid scroll bar, placed where the view is held.
    fn rows(&mut self, ui: &mut egui::Ui, lang: Lang, profile: &Profile, rows: &[Row<'_>]) {
        // show_rows adds the spacing between rows itself.
        let text_h = ui.text_style_height(&egui::TextStyle::Monospace);
        let row_h = text_h + ui.spacing().item_spacing.y;
        ui.spacing_mut().scroll = egui::style::ScrollStyle::solid();
        // No rubber band: it would spring an offset placed past last frame's end (the log grew,
        // or the panel was just opened) back, as if the technician had scrolled.
        ui.spacing_mut().scroll.kinetic.rubber_band = false;
        let content = rows.len() as f32 * row_h;
        let view_h = self
            .view_h
            .unwrap_or_else(|| ui.available_height() - ui.spacing().scroll.allocated_width());
        let offset = if self.follow {
            (content - view_h).max(0.0)
        } else {
            match self.anchor {
                Some((seq, into)) => {
                    rows.partition_point(|(s, _, _)| *s < seq) as f32 * row_h + into
                }
                None => self.placed.unwrap_or(0.0),
            }
        };
        let out = egui::ScrollArea::both()
            .auto_shrink(false)
            .scroll_bar_visibility(egui::scroll_area::ScrollBarVisibility::AlwaysVisible)
            .vertical_scroll_offset(offset)
            .show_rows(ui, text_h, rows.len(), |ui, range| {
                for (_, p, row) in &rows[range] {
                    let text = line_in(profile, p, *row, lang);
                    let color = row_color(ui, *row);
                    ui.add(
                        egui::Label::new(egui::RichText::new(text).monospace().color(color))
                            .wrap_mode(egui::TextWrapMode::Extend),
                    );
                }
            });
        let view_h = out.inner_rect.height();
        self.view_h = Some(view_h);
        let max = (out.content_size.y - view_h).max(0.0);
        let now = out.state.clamped_offset().y.clamp(0.0, max);
        let placed = offset.clamp(0.0, max);
        // The technician scrolled: up leaves the newest, to the bottom follows it again.
        if (now - placed).abs() > 0.5 {
            self.follow = now >= max - 1.0;
        }
        let top = ((now / row_h).floor() as usize).min(rows.len().saturating_sub(1));
        self.top = rows.get(top).map(|(s, _, _)| *s);
        self.anchor = (!self.follow)
            .then(|| self.top.map(|s| (s, now - top as f32 * row_h)))
            .flatten();
        self.placed = Some(now);
        let last_in_view = (((now + view_h) / row_h).ceil() as usize).min(rows.len());
        self.behind = match (rows.get(last_in_view.saturating_sub(1)), rows.last()) {
            (Some((_, _, seen)), Some((_, _, newest))) if !self.follow => {
                let secs = newest
                    .at()
                    .duration_since(seen.at())
                    .map_or(0.0, |d| d.as_secs_f64());
                Some((rows.len() - last_in_view, secs))
            }
            _ => None,
        };
    }

    /// Writes the rows shown to the typed (or chosen) file.
    /// Saves `rows` as text under a header: when, from which port, decoded with which profile.
    fn save(
        &self,
        lang: Lang,
        profile: &Profile,
        rows: &[Row<'_>],
        port: Option<&str>,
    ) -> Vec<Action> {
        let path = self.save_path.trim();
        if path.is_empty() {
            return vec![Action::Notify(Notice::error(Text::new(
                "save: give the file's path (type it, or Browse)",
                "保存:请给出文件路径(输入,或点击浏览)",
            )))];
        }
        let lines: Vec<String> = rows
            .iter()
            .map(|(_, p, e)| line(lang, profile, p, *e))
            .collect();
        let text = format!(
            "{}{}\n",
            save_header(profile, port, chrono::Local::now()),
            lines.join("\n")
        );
        match crate::document::write_atomic(std::path::Path::new(path), text.as_bytes()) {
            Ok(()) => vec![
                Action::RememberFile(FileKind::Packets, path.to_string()),
                Action::Notify(Notice::info(Text::new(
                    format!("{} line(s) saved to {path}", lines.len()),
                    format!("已保存 {} 行到 {path}", lines.len()),
                ))),
            ],
            Err(e) => vec![Action::Notify(Notice::error(e.said()))],
        }
    }
}

/// The colour of a row: sent frames plain, answers blue, frames that answer nothing they were
/// sent for (unsolicited, late) orange, damaged frames red, unanswered attempts dark orange.
fn row_color(ui: &egui::Ui, row: Shown<'_>) -> egui::Color32 {
    let e = match row {
        Shown::Frame(e) => e,
        Shown::NoAnswer(_) => return egui::Color32::from_rgb(230, 100, 30),
    };
    let unsolicited = matches!(&e.frame, Ok(p) if matches!(p.header, crate::packet::Header::MspReply { kind: crate::protocol::msp::ReplyKind::Async }));
    match (&e.frame, e.direction) {
        (Err(_), _) => egui::Color32::RED,
        (Ok(_), Direction::HostToDevice) => ui.visuals().text_color(),
        (Ok(_), Direction::DeviceToHost) if unsolicited || e.note.is_some() => {
            egui::Color32::from_rgb(220, 150, 0)
        }
        (Ok(_), Direction::DeviceToHost) => egui::Color32::from_rgb(40, 140, 200),
    }
}

/// Whether a packet of command `id` named `name` passes the monitor's filter `f` (trimmed, not
/// empty): its number in decimal (`28`) or hex (`0x1c`, `0X1C`), or a part of its name in any
/// case.
pub fn command_matches(f: &str, id: u8, name: &str) -> bool {
    let number = match f.strip_prefix("0x").or_else(|| f.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16).ok(),
        None => f.parse::<u8>().ok(),
    };
    number == Some(id) || name.to_ascii_lowercase().contains(&f.to_ascii_lowercase())
}

/// The lines above a saved log: when it was saved, the port and the profile it was decoded
/// with, each after `# `.
fn save_header(
    profile: &Profile,
    port: Option<&str>,
    at: chrono::DateTime<chrono::Local>,
) -> String {
    format!(
        "# botbench packet log, saved {}\n# port: {}\n# profile: {} ({})\n",
        at.format("%Y-%m-%d %H:%M:%S %:z"),
        port.unwrap_or("not connected"),
        profile.id,
        profile.name.en
    )
}

/// Where a capture is recorded to: the typed path, unless there is none or it names a file
/// that exists (a recording replaces nothing; the dialog asks before it does).
fn record_to(path: &str) -> Result<std::path::PathBuf, Notice> {
    let path = path.trim();
    if path.is_empty() {
        return Err(Notice::error(Text::new(
            "record: give the capture file's path (type it, or Browse)",
            "录制:请给出抓包文件的路径(输入或浏览)",
        )));
    }
    let p = std::path::PathBuf::from(path);
    if p.exists() {
        return Err(Notice::error(Text::new(
            format!("record: {path} exists; a recording replaces no file: give a new name"),
            format!("录制:{path} 已存在;录制不覆盖任何文件:请换一个文件名"),
        )));
    }
    Ok(p)
}

impl crate::ui::PanelId {
    /// Frames sent and received, live or from a capture file.
    pub const MONITOR: crate::ui::PanelId = crate::ui::PanelId::new("Monitor");
}

impl crate::ui::Panel for MonitorPanel {
    fn id(&self) -> crate::ui::PanelId {
        crate::ui::PanelId::MONITOR
    }

    fn name(&self, lang: Lang) -> &'static str {
        lang.tr("Packet monitor", "报文监视")
    }

    fn show(&mut self, ui: &mut egui::Ui, cx: &crate::ui::panel::Cx<'_>) -> Vec<Action> {
        self.draw(ui, cx.lang, cx.station)
    }

    fn restore(&mut self, settings: &crate::ui::Settings) {
        if let Some(p) = settings.file(FileKind::Packets) {
            self.save_path = p.to_string();
        }
        if let Some(p) = settings.file(FileKind::Capture) {
            self.capture_path = p.to_string();
        }
    }

    fn live(&self, station: &Station) -> bool {
        station.connected() && !station.packets.paused
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 25, item 10: the filter takes a command's number as the protocol documents write
    /// it (`0x1c`), in decimal, or a part of its name.
    #[test]
    fn the_filter_takes_hex_decimal_and_names() {
        for f in ["0x1c", "0X1C", "28", "version", "CMD_VER"] {
            assert!(command_matches(f, 0x1c, "CMD_VERSION"), "{f}");
        }
        for f in ["0x1d", "29", "0x", "0x1c1", "build"] {
            assert!(!command_matches(f, 0x1c, "CMD_VERSION"), "{f}");
        }
    }

    /// Issue 25, item 4e: an unanswered attempt during which this computer was held up says
    /// so on its row, in both languages; one on time does not.
    #[test]
    fn an_unanswered_attempt_on_a_held_up_computer_says_so_on_its_row() {
        let profile = crate::sim::msp_device::builtin_profile("window-cleaner").unwrap();
        let n = |host_late| NoAnswer {
            at: std::time::SystemTime::now(),
            command: 0x82,
            attempt: 1,
            attempts: 3,
            waited: std::time::Duration::from_millis(25),
            host_late,
        };
        let on_time = no_answer_said(&profile, &n(None));
        assert!(!on_time.en.contains("held up"), "{}", on_time.en);
        let late = no_answer_said(&profile, &n(Some(std::time::Duration::from_millis(31))));
        assert!(
            late.en.starts_with(&on_time.en)
                && late.en.contains("; this computer was held up 31 ms past the answer's deadline"),
            "{}",
            late.en
        );
        assert!(late.zh.starts_with(&on_time.zh) && late.zh.len() > on_time.zh.len());
        assert!(!late.zh.contains("held up"), "{}", late.zh);
    }

    #[test]
    fn a_saved_log_says_when_which_port_and_which_profile() {
        let profile = crate::sim::msp_device::builtin_profile("window-cleaner").unwrap();
        let at = chrono::Local::now();
        let h = save_header(&profile, Some("/dev/ttyUSB0"), at);
        assert!(h.contains(&at.format("%Y-%m-%d %H:%M:%S").to_string()), "{h}");
        assert!(h.contains("# port: /dev/ttyUSB0"), "{h}");
        assert!(h.contains("# profile: window-cleaner"), "{h}");
    }
}
