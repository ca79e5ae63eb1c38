//! Whether a window can be opened at all: a display server to show it on.

/// Why no window can be opened here, or `None` when a display may be there. On Linux and the
/// other Unix desktops (not macOS) a window needs an X11 or Wayland display, named by
/// `DISPLAY`, `WAYLAND_DISPLAY` or `WAYLAND_SOCKET`; with none of them set (an SSH session, a
/// service, CI) there is none. Windows and macOS always have one.
pub fn missing() -> Option<&'static str> {
    if cfg!(all(unix, not(target_os = "macos"))) {
        let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") && !set("WAYLAND_SOCKET") {
            return Some("neither DISPLAY nor WAYLAND_DISPLAY is set");
        }
    }
    None
}

/// Whether a window system's error says the display could not be reached (it is set but
/// gone: an X server that stopped, a forwarded display that timed out).
pub fn is_unreachable(error: &str) -> bool {
    let e = error.to_ascii_lowercase();
    e.contains("eventlooperror")
        || e.contains("failed to open display")
        || e.contains("xopendisplay")
        || e.contains("wayland_display")
}
