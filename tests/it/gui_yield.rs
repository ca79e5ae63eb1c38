//! The Yield view (issue 28): the window shows the records' report as `botbench report` gives
//! it, in both languages, and takes the records' location from its setting.

use crate::records::hand_set;
use crate::support::gui::{app, harness, settings, step_until};
use botbench::i18n::Lang;
use botbench::ops::records::SqliteStore;
use botbench::ui::PanelId;
use botbench::ui::settings::FileKind;
use botbench::ui::yield_view::YieldPanel;
use egui_kittest::kittest::Queryable;

fn hand_records(dir: &std::path::Path) -> String {
    let path = dir.join("yield.sqlite");
    let mut store = SqliteStore::open(&path).unwrap();
    for r in hand_set() {
        store.insert(&r).unwrap();
    }
    path.display().to_string()
}

#[test]
fn the_yield_view_shows_the_hand_sets_yields_in_both_languages() {
    let dir = crate::support::temp_dir();
    let records = hand_records(dir.path());
    for (lang, fpy, units) in [
        (Lang::En, "first-pass yield", "units"),
        (Lang::Zh, "直通率", "台数"),
    ] {
        let mut saved = settings(
            "/dev/botbench-no-port",
            "window-cleaner",
            PanelId::YIELD,
            lang,
        );
        saved.files.insert(FileKind::Records, records.clone());
        let mut h = harness(saved, botbench::link::PortOpener::system());
        // The view covers the last 7 days by default: the hand set is older, so all records.
        step_until(&mut h, "the view drawn", |a| {
            a.settings.panel == PanelId::YIELD
        });
        crate::support::gui::app_mut(&mut h)
            .panel_mut::<YieldPanel>()
            .period = botbench::ui::yield_view::Period::All;
        step_until(
            &mut h,
            "the report of every record",
            |a| matches!(a.station().records.report(), (Some(Ok(r)), false) if r.overall.units == 5),
        );
        h.run_steps(3);
        // Five units: 40 % first-pass, 60 % final (worked out by hand in records.rs).
        for text in ["40.0 %", "60.0 %", fpy, units, "A", "B"] {
            assert!(
                h.query_all_by_label(text).next().is_some(),
                "{lang:?}: no '{text}' on the Yield view"
            );
        }
        assert!(app(&h).station().records.error().is_none());
    }
}

#[test]
fn the_pareto_in_chinese_names_the_steps_botbench_knows_in_chinese() {
    use botbench::ui::yield_view::step_name;
    let zh = |s: &str| step_name(Lang::Zh, s);
    // The shipped self-test plan's steps (its zh map), the generated records' steps.
    assert_eq!(zh("Battery voltage"), "电池电压");
    assert_eq!(zh("Corner switches"), "四角开关");
    assert_eq!(zh("Spray pump"), "喷水泵");
    // The line station's steps, as their records name them.
    assert_eq!(
        zh("Self-test (window-cleaner-selftest)"),
        "自检(window-cleaner-selftest)"
    );
    assert_eq!(zh("Write result"), "写入测试结果");
    assert_eq!(zh("Measure Suction"), "测量 Suction");
    // The steps botbench records of its own runs: provisioning's, a preset apply's (a cancelled
    // or failed apply's Pareto showed "read before" in 中文).
    use botbench::ops::records::runs::{APPLY, READ_BEFORE};
    use botbench::ops::servo::provision::step;
    for s in step::ALL.into_iter().chain([READ_BEFORE, APPLY]) {
        assert!(
            !zh(s).chars().any(|c| c.is_ascii_lowercase()),
            "{s}: {}",
            zh(s)
        );
    }
    assert_eq!(zh("read before"), "写入前读取");
    // Another plan's step stays as recorded; English is always as recorded.
    assert_eq!(zh("Lid closes"), "Lid closes");
    assert_eq!(step_name(Lang::En, "Battery voltage"), "Battery voltage");
}
