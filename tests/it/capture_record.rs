//! Recording a session to pcapng and replaying it: through the link on pseudo-terminals, read
//! back with the pcap-file crate (and tshark where it is installed), bounded when the disk
//! stalls, and from the command line.

use crate::support::cli::{Sim, run};
use botbench::capture::{self, Capture, CaptureError, CaptureInfo, QUEUE_CHUNKS, ReplayDevice};
use botbench::link::{Link, LinkOptions, Opener, Request, Transport};
use botbench::profile::Profile;
use botbench::protocol::Direction;
use botbench::sim::{Faults, PtyServer, SharedDevice, SimTransport};
use std::io::Write;
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn window_cleaner() -> Arc<Profile> {
    crate::support::profile("window-cleaner")
}

fn options() -> LinkOptions {
    LinkOptions {
        start_session: false,
        reconnect: false,
        margin: Some(Duration::from_millis(200)),
        ..LinkOptions::default()
    }
}

/// The requests of a session: attitude (noisy: each answer differs), PWM, attitude again.
fn session(link: &Link) -> Vec<Vec<u8>> {
    [108u8, 130, 108, 108, 130, 108]
        .iter()
        .map(|&c| {
            link.client()
                .request(Request::new(c, Vec::new()).attempts(1))
                .expect("answered")
                .payload()
                .expect("a payload")
                .to_vec()
        })
        .collect()
}

/// Records `session` against the window-cleaner simulator on a pty into `path`.
fn record_window_cleaner(path: &std::path::Path) -> Vec<Vec<u8>> {
    let device: SharedDevice = Arc::new(Mutex::new(crate::support::window_cleaner()));
    // In lockstep with the link: the device answers in its own time whatever the load.
    let server = PtyServer::start_lockstep(device, Faults::default()).expect("pty");
    let info = CaptureInfo::new(server.path(), 115_200, "window-cleaner", None);
    let capture = Capture::create(path, info).expect("creates");
    let link = Link::open(
        capture.wrap(server.opener(115_200)),
        window_cleaner(),
        options(),
        None,
    )
    .expect("opens");
    let answers = session(&link);
    drop(link);
    let summary = capture.stop().expect("written");
    assert_eq!(summary.dropped, 0);
    assert!(summary.chunks >= 12, "{summary:?}");
    assert_eq!(
        summary.file_bytes,
        std::fs::metadata(path).expect("exists").len()
    );
    answers
}

#[test]
fn a_recorded_session_reads_back_with_its_bytes_directions_and_settings() {
    let dir = crate::support::temp_dir();
    let path = dir.path().join("wc.pcapng");
    let answers = record_window_cleaner(&path);
    let file = capture::read_path(&path).expect("reads");
    assert_eq!(file.info.profile, "window-cleaner");
    assert_eq!(file.info.baud, 115_200);
    assert_eq!(
        file.info.application,
        format!("botbench {}", env!("CARGO_PKG_VERSION"))
    );
    assert!(file.truncated.is_none());
    // Each request is one outbound chunk, in order.
    let out: Vec<&Chunk> = file
        .chunks
        .iter()
        .filter(|c| c.direction == Direction::HostToDevice)
        .collect();
    let commands: Vec<u8> = out.iter().map(|c| c.bytes[3]).collect();
    assert_eq!(commands, [108, 130, 108, 108, 130, 108]);
    // The inbound stream holds each answer's payload, in order.
    let frames = capture::frames(&file, botbench::profile::Protocol::Msp);
    let replies: Vec<Vec<u8>> = frames
        .iter()
        .filter(|f| f.direction == Direction::DeviceToHost)
        .map(|f| f.item.result.as_ref().expect("valid").payload.clone())
        .collect();
    assert_eq!(replies, answers);
    assert!(file.chunks.windows(2).all(|w| w[0].at_us <= w[1].at_us));
}

use botbench::capture::Chunk;

#[test]
fn the_file_is_pcapng_as_documented_for_any_reader() {
    use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
    use pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionOption;
    use pcap_file::pcapng::{Block, PcapNgReader};
    let dir = crate::support::temp_dir();
    let path = dir.path().join("wc.pcapng");
    record_window_cleaner(&path);
    let mut reader = PcapNgReader::new(std::fs::File::open(&path).unwrap()).expect("pcapng");
    let (mut idbs, mut epbs) = (0, 0);
    while let Some(block) = reader.next_block() {
        match block.expect("a whole block") {
            Block::InterfaceDescription(idb) => {
                idbs += 1;
                assert_eq!(u32::from(idb.linktype), 147, "LINKTYPE_USER0");
                assert!(
                    idb.options
                        .contains(&InterfaceDescriptionOption::IfTsResol(6))
                );
                assert!(
                    idb.options
                        .contains(&InterfaceDescriptionOption::IfSpeed(115_200))
                );
            }
            Block::EnhancedPacket(epb) => {
                epbs += 1;
                let flags = epb.options.iter().find_map(|o| match o {
                    EnhancedPacketOption::Flags(f) => Some(f & 0b11),
                    _ => None,
                });
                assert!(matches!(flags, Some(0b01 | 0b10)), "{flags:?}");
                assert_eq!(epb.original_len as usize, epb.data.len());
            }
            _ => {}
        }
    }
    assert_eq!(idbs, 1);
    assert!(epbs >= 12);
}

#[test]
fn tshark_reads_the_capture_where_it_is_installed() {
    let mut version = Command::new("tshark");
    version.arg("--version").stdin(std::process::Stdio::null());
    let Ok(version) = crate::support::cli::try_watched(&mut version, "tshark --version") else {
        eprintln!("tshark is not installed: the pcap-file reader test stands for it");
        return;
    };
    assert_eq!(version.code, 0, "{}", version.text());
    let dir = crate::support::temp_dir();
    let path = dir.path().join("wc.pcapng");
    record_window_cleaner(&path);
    let file = capture::read_path(&path).expect("reads");
    let o = crate::support::cli::watched(
        Command::new("tshark")
            .args(["-r", path.to_str().unwrap(), "-T", "fields"])
            .args(["-e", "frame.len", "-e", "frame.time_epoch"])
            .args(["-e", "frame.packet_flags_direction"])
            .stdin(std::process::Stdio::null()),
        "tshark",
    );
    assert_eq!(o.code, 0, "{}", o.text());
    let rows: Vec<Vec<String>> = o
        .out
        .lines()
        .map(|l| l.split('\t').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), file.chunks.len());
    for (row, c) in rows.iter().zip(&file.chunks) {
        assert_eq!(row[0], c.bytes.len().to_string());
        // Microseconds since the epoch, as tshark prints seconds.
        let t: f64 = row[1].parse().expect("a time");
        assert!(
            (t - c.at_us as f64 / 1e6).abs() < 1e-5,
            "{t} vs {}",
            c.at_us
        );
        let dir = i64::from_str_radix(row[2].trim_start_matches("0x"), 16).expect("a flag");
        let want = match c.direction {
            Direction::DeviceToHost => 1,
            Direction::HostToDevice => 2,
        };
        assert_eq!(dir, want, "{row:?}");
    }
}

#[test]
fn a_window_cleaner_capture_replays_the_same_values_on_a_pty_and_in_process() {
    let dir = crate::support::temp_dir();
    let path = dir.path().join("wc.pcapng");
    let answers = record_window_cleaner(&path);
    let file = capture::read_path(&path).expect("reads");

    // On a pseudo-terminal, as `botbench sim replay` serves it.
    let device: SharedDevice = Arc::new(Mutex::new(ReplayDevice::new(&file).unwrap()));
    let server = PtyServer::start_lockstep(device, Faults::default()).expect("pty");
    let link =
        Link::open(server.opener(115_200), window_cleaner(), options(), None).expect("opens");
    assert_eq!(session(&link), answers);
    drop(link);

    // In process.
    let device: SharedDevice = Arc::new(Mutex::new(ReplayDevice::new(&file).unwrap()));
    let mut transport = Some(SimTransport::new(
        device,
        115_200,
        Faults::default(),
        "replay",
    ));
    let opener: Opener = Box::new(move || {
        transport
            .take()
            .map(|t| Box::new(t) as Box<dyn Transport>)
            .ok_or_else(|| botbench::link::LinkError::Disconnected("replay ended".into()))
    });
    let link = Link::open(opener, window_cleaner(), options(), None).expect("opens");
    assert_eq!(session(&link), answers);
}

/// A disk that takes nothing until it is let go.
struct StalledDisk(crossbeam_channel::Receiver<()>);

impl Write for StalledDisk {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let _ = self.0.recv_timeout(crate::support::PATIENCE);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_stalled_disk_drops_and_counts_chunks_and_never_blocks_the_link() {
    let (go, gate) = crossbeam_channel::unbounded();
    // The header goes through.
    go.send(()).unwrap();
    let info = CaptureInfo::new("test", 115_200, "window-cleaner", None);
    let capture = Capture::to_writer(StalledDisk(gate), info, "stalled".into()).expect("starts");
    let n = QUEUE_CHUNKS * 3;
    for i in 0..n {
        capture.record(Direction::DeviceToHost, &[i as u8; 8]);
        assert!(capture.queued() <= QUEUE_CHUNKS);
    }
    // The 64 KiB buffer takes about 1200 chunks before the writer blocks; the queue the rest.
    assert!(capture.dropped() > 0);
    assert!(capture.peak_queue() <= QUEUE_CHUNKS);
    drop(go); // The disk comes back.
    let summary = capture.stop().expect("written");
    assert_eq!(summary.chunks + summary.dropped, n as u64);
}

#[test]
fn a_drop_is_marked_on_the_next_chunk_written() {
    let (go, gate) = crossbeam_channel::unbounded::<()>();
    let dir = crate::support::temp_dir();
    let path = dir.path().join("drops.pcapng");
    struct Gated(std::fs::File, crossbeam_channel::Receiver<()>);
    impl Write for Gated {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let _ = self.1.recv_timeout(crate::support::PATIENCE);
            self.0.write(buf)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.0.flush()
        }
    }
    go.send(()).unwrap();
    let info = CaptureInfo::new("test", 115_200, "window-cleaner", None);
    let file = Gated(std::fs::File::create(&path).unwrap(), gate);
    let capture = Capture::to_writer(file, info, "gated".into()).expect("starts");
    for i in 0..QUEUE_CHUNKS * 3 {
        capture.record(Direction::HostToDevice, &[i as u8]);
    }
    let dropped = capture.dropped();
    assert!(dropped > 0);
    drop(go);
    // Once the writer has caught up, the next chunk is taken and carries the count.
    crate::support::wait_until("the writer to catch up", || capture.queued() == 0);
    capture.record(Direction::HostToDevice, b"after the stall");
    capture.stop().expect("written");
    let back = capture::read_path(&path).expect("reads");
    let marked: u64 = back.chunks.iter().map(|c| c.dropped_before).sum();
    assert_eq!(marked, dropped, "every drop is marked in the file");
}

#[test]
fn a_failing_disk_is_an_error_when_recording_stops() {
    struct Full;
    impl Write for Full {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::Error::other("No space left on device"))
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let info = CaptureInfo::new("test", 115_200, "window-cleaner", None);
    let err = Capture::to_writer(std::io::BufWriter::new(Full), info, "full".into()).unwrap_err();
    assert!(matches!(err, CaptureError::Write(_)), "{err}");
    assert!(
        Capture::create(
            std::path::Path::new("/nonexistent/dir/x.pcapng"),
            Default::default()
        )
        .is_err()
    );
}

#[test]
fn bad_files_get_clear_errors_and_a_cut_off_file_keeps_what_came_before() {
    let dir = crate::support::temp_dir();
    let path = dir.path().join("wc.pcapng");
    record_window_cleaner(&path);
    let whole = capture::read_path(&path).expect("reads");
    let bytes = std::fs::read(&path).unwrap();
    // Cut in the middle of the last block.
    let cut = capture::read(&bytes[..bytes.len() - 5]).expect("reads what is whole");
    assert!(cut.truncated.is_some());
    assert_eq!(cut.chunks[..], whole.chunks[..whole.chunks.len() - 1]);
    // Not pcapng at all; empty.
    for junk in [&b"hello, this is not a capture"[..], &[][..]] {
        let e = capture::read(junk).unwrap_err();
        assert!(matches!(e, CaptureError::Format(_)), "{e}");
    }
    let e = capture::read_path(&dir.path().join("missing.pcapng")).unwrap_err();
    assert!(matches!(e, CaptureError::Open { .. }), "{e}");
}

#[test]
fn the_command_line_records_with_capture_prints_it_and_replays_it() {
    let dir = crate::support::temp_dir();
    let path = dir.path().join("cli.pcapng");
    let file = path.to_str().unwrap();
    let sim = Sim::start(&["window-cleaner"]);
    let get = |sim: &Sim, capture: Option<&str>| {
        let mut args = vec!["msp", "--port", &sim.path];
        if let Some(f) = capture {
            args.extend(["--capture", f]);
        }
        let ran = sim.run(&[&args[..], &["get", "108", "--json"]].concat());
        assert_eq!(ran.code, 0, "{}", ran.err);
        ran
    };
    let recorded = get(&sim, Some(file));
    assert!(
        recorded.err.contains("capture"),
        "the capture is summed up on stderr"
    );

    let ran = run(&["frame", "decode", "--capture", file, "--json"]);
    assert_eq!(ran.code, 0, "{}", ran.err);
    let docs = ran.json_lines();
    assert!(docs.iter().any(|d| d["command"] == 108));
    assert!(docs.iter().all(|d| d["at_us"].as_u64().is_some()));

    let replay = Sim::start(&["replay", file]);
    let replayed = get(&replay, None);
    assert_eq!(
        replayed.out, recorded.out,
        "the replay answers what the device answered"
    );

    assert_eq!(run(&["sim", "replay"]).code, 2, "a file is needed");
}
