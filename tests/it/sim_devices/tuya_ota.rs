//! The Tuya MCU simulator's OTA upgrade: every packet size, and the faults it can show.

use super::*;

// ---------------------------------------------------------------- OTA

fn ota_packet(offset: u32, data: &[u8]) -> Vec<u8> {
    let mut d = offset.to_be_bytes().to_vec();
    d.extend_from_slice(data);
    module(tcmd::OTA_PACKET, &d)
}

fn is_ack(out: &[Outgoing]) -> bool {
    matches!(tuya_frames(out).as_slice(), [f] if f.command == tcmd::OTA_PACKET && f.data.is_empty())
}

#[test]
fn ota_of_64_kib_at_every_packet_size() {
    let img = image(64 * 1024 + 7);
    for (answer, data, size) in [
        (OtaPacketAnswer::Option(0), vec![0], 256),
        (OtaPacketAnswer::Option(1), vec![1], 512),
        (OtaPacketAnswer::Option(2), vec![2], 1024),
        (OtaPacketAnswer::Empty, vec![], 256),
    ] {
        let now = Instant::now();
        let mut mcu = TuyaMcu::new(TuyaConfig {
            ota_packet: answer,
            ..TuyaConfig::default()
        });
        let start = module(tcmd::OTA_START, &(img.len() as u32).to_be_bytes());
        let f = tuya_frames(&mcu.receive(&start, 9600, now));
        assert_eq!((f[0].command, &f[0].data), (tcmd::OTA_START, &data));
        for (i, chunk) in img.chunks(size).enumerate() {
            let out = mcu.receive(&ota_packet((i * size) as u32, chunk), 9600, now);
            assert!(is_ack(&out), "packet {i} at size {size}");
        }
        assert!(matches!(mcu.ota_state(), OtaState::Receiving { .. }));
        assert!(is_ack(&mcu.receive(
            &ota_packet(img.len() as u32, &[]),
            9600,
            now
        )));
        assert_eq!(
            mcu.ota_state(),
            &OtaState::Complete {
                size: img.len() as u32,
                crc32: tuya_mcu::crc32(&img)
            }
        );
        assert_eq!(mcu.ota_image(), img.as_slice());
    }
    assert_eq!(tuya_mcu::crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn ota_faults() {
    let now = Instant::now();
    let img = image(4096);
    let start = module(tcmd::OTA_START, &4096u32.to_be_bytes());

    // stop_acking_at: acks stop at the first packet at or past the offset, for good.
    let mut mcu = TuyaMcu::new(TuyaConfig {
        stop_acking_at: Some(1024),
        ..TuyaConfig::default()
    });
    mcu.receive(&start, 9600, now);
    let acks: Vec<bool> = img
        .chunks(256)
        .enumerate()
        .map(|(i, c)| is_ack(&mcu.receive(&ota_packet(i as u32 * 256, c), 9600, now)))
        .collect();
    assert_eq!(acks.iter().filter(|a| **a).count(), 4);
    assert!(acks[..4].iter().all(|a| *a));
    assert!(
        mcu.receive(&ota_packet(0, &img[..256]), 9600, now)
            .is_empty()
    );

    // A packet larger than agreed: silent abort; later packets are ignored.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert!(
        mcu.receive(&ota_packet(256, &img[256..768]), 9600, now)
            .is_empty()
    );
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));
    assert!(
        mcu.receive(&ota_packet(256, &img[256..512]), 9600, now)
            .is_empty()
    );

    // A gap in the offsets aborts; a resent last packet is acked again without being stored twice.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert!(is_ack(&mcu.receive(&ota_packet(0, &img[..256]), 9600, now)));
    assert_eq!(mcu.ota_image().len(), 256);
    assert!(
        mcu.receive(&ota_packet(512, &img[512..768]), 9600, now)
            .is_empty()
    );
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));

    // Ending early is no success.
    let mut mcu = TuyaMcu::default();
    mcu.receive(&start, 9600, now);
    mcu.receive(&ota_packet(0, &img[..256]), 9600, now);
    assert!(mcu.receive(&ota_packet(4096, &[]), 9600, now).is_empty());
    assert!(matches!(mcu.ota_state(), OtaState::Aborted { .. }));

    // Packets with no update started are ignored.
    let mut mcu = TuyaMcu::default();
    assert!(
        mcu.receive(&ota_packet(0, &img[..256]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.ota_state(), &OtaState::Idle);
}
