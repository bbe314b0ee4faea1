use super::header::*;
use super::*;

#[test]
fn header_lines_are_read_whatever_their_spacing() {
    assert_eq!(channel_number("Chan  5: 90 Deg   Location: deck"), Some(5));
    assert_eq!(channel_number("CHAN 12:  Up"), Some(12));
    assert_eq!(channel_number("Station channel list"), None);
    assert_eq!(file_channel_number("station.zip:CHAN005.V2"), Some(5));
    assert_eq!(file_channel_number("dir/26327_ch3.v2"), Some(3));
    let d = "  8000 points of accel data equally spaced at   .005 sec, in cm/sec2.  (8F10.3)";
    assert_eq!(number_after(d, "spaced at"), Some(0.005));
    assert_eq!(field_width(d), Some(10));
    assert_eq!(
        fields("-1234.567-1234.567    1.000   ", 9),
        ["-1234.567", "-1234.567", "    1.000"]
    );
    assert_eq!(
        record_start("Rcrd of Mon Nov 23, 2026 02:00:00.5 PST"),
        crate::io::wire::parse_timestamp("2026-11-23T10:00:00.5Z")
    );
    assert_eq!(record_start("Rcrd of Mon Nov 23, 2026 02:00:00.0 CET"), None);
}

#[test]
fn a_short_or_garbled_channel_is_an_error_naming_it() {
    let good = "Chan  2: 90 Deg\n     3 points of accel data equally spaced at  0.010 sec, in cm/sec2. (8f10.5)\n   1.00000   2.00000   3.00000\n";
    let read = |text: &str, name: &str| read_v2(&[(text.as_bytes().to_vec(), name.to_string())]);
    let s = read(good, "a.V2").unwrap();
    assert_eq!(s.channels[0].name, "ch2");
    assert_eq!(s.channels[0].data, [1.0, 2.0, 3.0]);
    assert_eq!(s.channels[0].unit.as_deref(), Some("cm/s^2"));
    assert_eq!(s.fs, Some(100.0));
    let short = good.replace("   3.00000", "");
    let e = read(&short, "a.V2").unwrap_err().to_string();
    assert!(e.contains("a.V2, channel 2") && e.contains("2 of the 3"), "{e}");
    let garbled = good.replace("2.00000", "2.0x000");
    let e = read(&garbled, "a.V2").unwrap_err().to_string();
    assert!(e.contains("is not a number"), "{e}");
    let e = read("just text\n", "b.V2").unwrap_err().to_string();
    assert!(e.contains("not a Volume 2 file"), "{e}");
}

/// A channel in the CDMG's upper-case layout of the 1980s (abridged: the
/// integer and real headers left out), as the Painter Street records of
/// 1980–1992 have it; `trigger` the clock of its `TRIGGER TIME` line.
fn older_layout(station: u32, trigger: &str, n: usize) -> String {
    let values: String = (0..n)
        .map(|i| format!("{:10.3}", 10.0 * (i as f64 * 0.3).sin()))
        .collect::<Vec<_>>()
        .chunks(8)
        .map(|c| c.concat() + "\r\n")
        .collect();
    format!(
        "CORRECTED ACCELEROGRAM   89324-C0138-80314.03       CHAN  2: UP          FROM\r\n\
         89324-C0138-80314.03               TRIGGER TIME: 11/08/80, {trigger} UTC\r\n\
         CHAN  2: 270 DEG  (STA CHN: {station})     LOCATION: DECK, NEAR EAST ABUTMENT\r\n\
         \x20 {n} POINTS OF INSTRUMENT- AND BASELINE-CORRECTED ACCEL, VELOC AND DISPL DATA\r\n\
         AT EQUALLY-SPACED INTERVALS OF    .020  SEC.\r\n\
         \x20     3  {n} POINTS OF ACCEL DATA EQUALLY SPACED AT  .020 SEC.  (UNITS: CM/SEC/SEC)\r\n\
         {values}\x20{n} POINTS OF VELOC DATA EQUALLY SPACED AT  .020 SEC.  (UNITS: CM/SEC)\r\n\
         \x20     1.000\r\n/&  ----------  END OF DATA FOR CHANNEL  2  ----------\r\n"
    )
}

#[test]
fn the_older_upper_case_layout_reads_with_its_trigger_time() {
    let files = [
        (older_layout(11, "10:27:55.4", 20).into_bytes(), "CHAN03.V2".to_string()),
        (older_layout(14, "10:27:55.4", 17).into_bytes(), "CHAN13.V2".to_string()),
    ];
    let s = read_v2(&files).unwrap();
    assert_eq!(s.fs, Some(50.0));
    assert_eq!(s.start_ns, crate::io::wire::parse_timestamp("1980-11-08T10:27:55.4Z"));
    let names: Vec<&str> = s.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["ch11", "ch14"]);
    assert_eq!(s.channels[0].unit.as_deref(), Some("cm/s^2"));
    assert!(s.channels.iter().all(|c| c.data.len() == 17));
    assert_eq!(s.channels[0].data[1], 2.955); // 10 sin 0.3, as printed
                                              // The 20-point channel lost 3 points to the common span, and says so.
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(
        s.notes[0].contains("ch11 (0.40 s)") && !s.notes[0].contains("ch14"),
        "{:?}",
        s.notes
    );
    let listed = list_v2(&files).unwrap();
    assert_eq!(
        (listed[0].direction.as_str(), listed[0].location.as_str()),
        ("270 DEG", "DECK, NEAR EAST ABUTMENT")
    );
    // Seconds the film did not show: no start, for either channel.
    let unread = older_layout(11, "10:27:XX.X", 20);
    assert_eq!(read_v2(&[(unread.into_bytes(), "a.V2".into())]).unwrap().start_ns, None);
}

#[test]
fn start_lines_with_a_flag_or_a_two_digit_year_are_read() {
    let at = |t: &str| crate::io::wire::parse_timestamp(t);
    assert_eq!(
        record_start("Rcrd of Tue Dec 20, 2022 02:34:24.0 PST*"),
        at("2022-12-20T10:34:24Z")
    );
    assert_eq!(
        record_start("Record of Sat Jul 31, 2021 12:00:01.5 PDT*"),
        at("2021-07-31T19:00:01.5Z")
    );
    assert_eq!(
        trigger_start("  TRIGGER TIME: 11/21/86, 23:33:12.6 GMT"),
        at("1986-11-21T23:33:12.6Z")
    );
    assert_eq!(
        trigger_start("TRIGGER TIME: 01/02/05, 00:00:01.0 UTC"),
        at("2005-01-02T00:00:01Z")
    );
    assert_eq!(trigger_start("TRIGGER TIME: 12/16/82, 06:53:XX.X UTC"), None);
    assert_eq!(trigger_start("TRIGGER TIME: 12/16/82, 06:53:99.0 UTC"), None);
}

#[test]
fn an_empty_file_is_called_empty() {
    for bytes in [&b""[..], b"  \r\n\n"] {
        let e = read_v2(&[(bytes.to_vec(), "e.V2".into())]).unwrap_err().to_string();
        assert!(e.contains("e.V2") && e.contains("empty"), "{e}");
    }
}

#[test]
fn a_channel_twice_is_taken_once_when_both_copies_agree() {
    let one = older_layout(11, "10:27:55.4", 20);
    let same = [
        (one.clone().into_bytes(), "all.V2".into()),
        (one.clone().into_bytes(), "CHAN03.V2".into()),
    ];
    let s = read_v2(&same).unwrap();
    assert_eq!(s.channels.len(), 1);
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    let changed = one.replacen("     2.955", "     2.956", 1);
    assert_ne!(changed, one);
    let e = read_v2(&[
        (one.into_bytes(), "all.V2".into()),
        (changed.into_bytes(), "CHAN03.V2".into()),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("CHAN03.V2") && e.contains("channel 11 is also in all.V2") && e.contains("differ by up to"),
        "{e}"
    );
}

/// Two channels of two recorders (station channels 7 and 15, 100 and
/// 200 Hz, started a sample apart), for the damaged-input properties.
fn two_recorders() -> String {
    let channel = |k: u32, station: u32, dt: f64, start: &str, n: usize| {
        let values: String = (0..n)
            .map(|i| format!("{:10.5}", (i as f64 * 0.7).sin()))
            .collect::<Vec<_>>()
            .chunks(8)
            .map(|c| c.concat() + "\n")
            .collect();
        format!(
            "Chan  {k}:  Tran    (Sta Chn: {station})     Location: Deck\nRcrd of Mon Nov 23, 2026 {start} UTC\n  {n} points of accel data equally spaced at   {dt} sec, in cm/sec2. (8f10.5)\n{values}/&  ---------- End of data for channel  {k} ----------\n"
        )
    };
    channel(1, 7, 0.01, "10:00:00.0", 40) + &channel(1, 15, 0.005, "10:00:00.01", 80)
}

#[test]
fn two_recorders_come_on_one_grid_by_station_channel() {
    let s = read_v2(&[(two_recorders().into_bytes(), "station.V2".into())]).unwrap();
    let names: Vec<&str> = s.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["ch7", "ch15"]);
    assert_eq!(s.fs, Some(100.0));
    // 0.39 s in common at 100 Hz, from the later start.
    assert!(s.channels.iter().all(|c| c.data.len() == 39));
    assert_eq!(s.start_ns, crate::io::wire::parse_timestamp("2026-11-23T10:00:00.01Z"));
    // ch7 cut at its second sample (the file's five decimals of sin 0.7).
    assert_eq!(s.channels[0].data[0], 0.64422);
}

proptest::proptest! {
    #[test]
    fn damaged_stations_are_errors_never_panics(
        flips in proptest::collection::vec((proptest::prelude::any::<proptest::sample::Index>(), proptest::prelude::any::<u8>()), 0..8),
        cut in proptest::prelude::any::<proptest::sample::Index>(),
    ) {
        let mut bytes = two_recorders().into_bytes();
        for (i, b) in &flips {
            let k = i.index(bytes.len());
            bytes[k] = *b;
        }
        bytes.truncate(cut.index(bytes.len() + 1));
        let files = [(bytes, "station.V2".to_string())];
        if let Ok(s) = read_v2(&files) {
            proptest::prop_assert!(s.channels.iter().all(|c| c.data.len() >= 2));
        }
        let _ = list_v2(&files);
    }
}
