//! Recording the link to a capture file, and viewing a capture offline (issue 16).

use super::{Notice, OfflineCapture, Station};
use crate::capture::{self, Capture, CaptureInfo};
use crate::i18n::Text;
use crate::link::LogEntry;
use crate::ui::zh::Zh;
use std::path::Path;
use std::time::{Duration, UNIX_EPOCH};

impl Station {
    /// Starts recording the link's bytes to `path` (replacing a recording under way); says in
    /// the status line why not (not connected, the file cannot be created).
    pub fn start_capture(&mut self, path: &Path) {
        let Some(conn) = &self.link.connection else {
            self.notify(Notice::error(Text::new(
                "connect first: a capture records a port session",
                "请先连接:抓包记录的是一次串口会话",
            )));
            return;
        };
        let baud = self.link.baud().unwrap_or(0);
        let info = CaptureInfo::new(
            &conn.target.label(),
            baud,
            &self.device.profile.id,
            self.link.options.margin,
        );
        match Capture::create(path, info) {
            Ok(c) => {
                if let Some(old) = self.packets.tap.start(c) {
                    let _ = old.stop();
                }
                // The device is identified again into the recording (MSP: CMD_VERSION, then
                // CMD_BUILD_INFO; nothing on other protocols), so that a replay of it
                // identifies as the session did (`botbench sim replay`).
                self.send(crate::link::LinkCommand::Identify);
                self.notify(Notice::info(Text::new(
                    format!("recording to {}", path.display()),
                    format!("正在录制到 {}", path.display()),
                )));
            }
            Err(e) => self.notify(Notice::error(e.said())),
        }
    }

    /// Stops recording, if recording, and says what the file holds.
    pub fn stop_capture(&mut self) {
        let Some(c) = self.packets.tap.stop() else {
            return;
        };
        let notice = match c.stop() {
            Ok(s) if s.dropped > 0 => Notice::error(Text::new(
                format!(
                    "capture {}: {} chunks, {} bytes; {} chunks lost (the disk could not keep up)",
                    c.path(),
                    s.chunks,
                    s.file_bytes,
                    s.dropped
                ),
                format!(
                    "抓包 {}:{} 块,{} 字节;丢失 {} 块(磁盘跟不上)",
                    c.path(),
                    s.chunks,
                    s.file_bytes,
                    s.dropped
                ),
            )),
            Ok(s) => Notice::info(Text::new(
                format!(
                    "capture {}: {} chunks, {} bytes",
                    c.path(),
                    s.chunks,
                    s.file_bytes
                ),
                format!("抓包 {}:{} 块,{} 字节", c.path(), s.chunks, s.file_bytes),
            )),
            Err(e) => Notice::error(
                Text::new(
                    format!("capture {}", c.path()),
                    format!("抓包 {}", c.path()),
                )
                .then(": ", &e.said()),
            ),
        };
        self.notify(notice);
    }

    /// The capture being recorded, if any (its size grows in the monitor).
    pub fn recording(&self) -> Option<Capture> {
        self.packets.tap.current()
    }

    /// Opens a capture file for the packet monitor, decoded with its profile (else the
    /// current one).
    pub fn open_capture(&mut self, path: &Path) {
        let file = match capture::read_path(path) {
            Ok(f) => f,
            Err(e) => return self.notify(Notice::error(e.said())),
        };
        let profile = match self.registry.get(&file.info.profile) {
            Ok(p) => p,
            Err(_) => self.device.profile.clone(),
        };
        let entries = capture::frames(&file, profile.protocol)
            .into_iter()
            .map(|f| LogEntry {
                at: UNIX_EPOCH + Duration::from_micros(f.at_us),
                direction: f.direction,
                frame: f.item.result,
                note: None,
            })
            .collect();
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into(),
        );
        self.notify(Notice::info(Text::new(
            format!(
                "{name}: {} chunks, profile {}",
                file.chunks.len(),
                profile.id
            ),
            format!("{name}:{} 块,设备配置 {}", file.chunks.len(), profile.id),
        )));
        self.packets.offline = Some(OfflineCapture {
            name,
            profile,
            entries,
            truncated: file.truncated,
        });
    }

    /// Back to the live frames.
    pub fn close_capture(&mut self) {
        self.packets.offline = None;
    }
}
