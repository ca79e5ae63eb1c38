//! A panel is one file (or folder) of `ui/` and one line in the list (`panels!` in `ui/mod.rs`),
//! as egui's demo app keeps its demos: the file implements [`Panel`], the line names its module
//! and type. Everything the app does with panels goes through the trait: the navigation (which
//! panels a device has, their names), drawing (`show` returns [`Action`]s), what a panel does
//! every frame (`tick`), what it forgets on another connection or unit (`forget`), the output of
//! the jobs it started (`on_output`, typed by the panel itself), the files it remembers
//! (`restore`), and the parts the screenshot tour walks (`parts`, `show_part`).

use super::station::Station;
use super::{Action, Settings};
use crate::i18n::Lang;
use crate::profile::PanelKind;
use eframe::egui;
use std::any::Any;

/// A panel's id: its name in the saved settings (`panel: Tuning`), after `--panel` on the
/// command line, and in a screenshot's file name. Each panel's file defines its own
/// (`PanelId::TUNING` in `tuning/mod.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PanelId(&'static str);

impl PanelId {
    /// The id `name` (a panel's file gives its own, once).
    pub const fn new(name: &'static str) -> Self {
        Self(name)
    }

    /// The id as written: `Tuning`.
    pub fn as_str(self) -> &'static str {
        self.0
    }

    /// The id of the panel in the list named `name` (as written: `SelfTest`), if there is one.
    pub fn parse(name: &str) -> Option<PanelId> {
        super::panels()
            .iter()
            .map(|p| p.id())
            .find(|id| id.0 == name)
    }

    /// The name in `lang` of the panel in the list with this id (the id itself for another).
    pub fn name(self, lang: Lang) -> &'static str {
        super::panels()
            .iter()
            .find(|p| p.id() == self)
            .map_or(self.0, |p| p.name(lang))
    }

    /// Every panel's id, in the list's order.
    pub fn all() -> Vec<PanelId> {
        super::panels().iter().map(|p| p.id()).collect()
    }
}

impl std::fmt::Display for PanelId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

/// Saved as an enum's unit variant (`panel: Tuning`), as when the ids were an enum: settings
/// saved by an earlier version still load.
impl serde::Serialize for PanelId {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_unit_variant("PanelId", 0, self.0)
    }
}

impl<'de> serde::Deserialize<'de> for PanelId {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("PanelId", &[], IdVisitor)
    }
}

struct IdVisitor;

impl IdVisitor {
    fn known<E: serde::de::Error>(name: &str) -> Result<PanelId, E> {
        PanelId::parse(name).ok_or_else(|| E::custom(format!("unknown panel '{name}'")))
    }
}

impl<'de> serde::de::Visitor<'de> for IdVisitor {
    type Value = PanelId;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a panel's id, e.g. Tuning")
    }

    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<PanelId, E> {
        Self::known(v)
    }

    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<PanelId, A::Error> {
        use serde::de::VariantAccess;
        let (Ident(name), variant) = data.variant()?;
        variant.unit_variant()?;
        Self::known(&name)
    }
}

/// An enum variant's name, read as the identifier it is (RON writes it bare: `Tuning`).
struct Ident(String);

impl<'de> serde::Deserialize<'de> for Ident {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Ident;

            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a panel's name")
            }

            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Ident, E> {
                Ok(Ident(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

/// What a panel reads while it draws: the language, the saved settings and the station it
/// shows.
pub struct Cx<'a> {
    /// The window's language.
    pub lang: Lang,
    /// The saved settings.
    pub settings: &'a Settings,
    /// The station shown.
    pub station: &'a Station,
}

/// Why a panel forgets what it showed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Forget {
    /// A new connection was opened: maybe another device, of another kind.
    Connection,
    /// The link came up again, or the device answers again after silence: maybe another unit
    /// on the same fixture (it is identified again). The panel may ask to read it.
    Unit,
}

/// The output of a job for the panel that started it: a value of that panel's own type (its
/// `Output`), sent with [`super::jobs::JobSink::panel`] and taken back with [`Self::take`].
pub struct PanelOutput(Box<dyn Any + Send>);

impl PanelOutput {
    /// `out`, for the panel that started the job.
    pub fn new<T: Any + Send>(out: T) -> Self {
        Self(Box::new(out))
    }

    /// The output, if it is a `T` (a panel's own type); `None` for another type.
    pub fn take<T: Any>(self) -> Option<T> {
        self.0.downcast::<T>().ok().map(|b| *b)
    }
}

impl std::fmt::Debug for PanelOutput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PanelOutput(..)")
    }
}

/// A panel of the window. Only `id`, `name` and `show` are needed; the rest do nothing unless
/// a panel has something to do there.
pub trait Panel: Any {
    /// Its id (see [`PanelId`]).
    fn id(&self) -> PanelId;

    /// Its name in the navigation, in `lang`.
    fn name(&self, lang: Lang) -> &'static str;

    /// The profile's name for it, when only devices whose profile names it have it (with the
    /// capability bit the profile gives it); `None`: every device has it.
    fn kind(&self) -> Option<PanelKind> {
        None
    }

    /// Draws it; returns what it asks the app to do.
    fn show(&mut self, ui: &mut egui::Ui, cx: &Cx<'_>) -> Vec<Action>;

    /// Called every frame whichever panel is shown (a dead-man, answers to take).
    fn tick(&mut self, _station: &Station) -> Vec<Action> {
        Vec::new()
    }

    /// Forgets what it showed of the last device or unit (see [`Forget`]); may ask to read the
    /// new one.
    fn forget(&mut self, _station: &Station, _why: Forget) -> Vec<Action> {
        Vec::new()
    }

    /// Takes what one of the jobs it started reported.
    fn on_output(&mut self, _out: PanelOutput, _station: &Station) -> Vec<Action> {
        Vec::new()
    }

    /// Takes the files last used from the saved settings, into its boxes.
    fn restore(&mut self, _settings: &Settings) {}

    /// The parts it shows one at a time, by name (tabs, groups): the screenshot tour shoots
    /// each. None: it is shown whole.
    fn parts(&self, _station: &Station) -> Vec<String> {
        Vec::new()
    }

    /// Shows part `part` of [`Self::parts`].
    fn show_part(&mut self, _part: usize, _station: &Station) {}

    /// Whether it shows live data now (the window then redraws at the live rate).
    fn live(&self, _station: &Station) -> bool {
        false
    }

    /// Whether it shows STOP itself (the navigation's is then left out while it is shown).
    fn shows_stop(&self) -> bool {
        false
    }
}

/// The panels of one station, each with its own state: the list's (`panels!` in `ui/mod.rs`).
pub struct Panels(Vec<Box<dyn Panel>>);

impl Default for Panels {
    /// A fresh panel of each kind in the list.
    fn default() -> Self {
        Self(super::panels())
    }
}

impl Panels {
    /// No panels (a station's panels while one of them draws it: see
    /// [`Station::with_panels`]).
    pub fn none() -> Self {
        Self(Vec::new())
    }

    /// Every panel, in the list's order.
    pub fn iter(&self) -> impl Iterator<Item = &dyn Panel> {
        self.0.iter().map(|p| p.as_ref())
    }

    /// The panel `id`.
    pub fn find(&self, id: PanelId) -> Option<&dyn Panel> {
        self.iter().find(|p| p.id() == id)
    }

    /// The panel of type `T`.
    pub fn get<T: Panel>(&self) -> Option<&T> {
        self.0
            .iter()
            .find_map(|p| (p.as_ref() as &dyn Any).downcast_ref::<T>())
    }

    /// The panel of type `T`, to change.
    pub fn get_mut<T: Panel>(&mut self) -> Option<&mut T> {
        self.0
            .iter_mut()
            .find_map(|p| (p.as_mut() as &mut dyn Any).downcast_mut::<T>())
    }

    /// The panels `station`'s device has, in the navigation's order: those its profile names,
    /// in the profile's order, but a panel whose CMD_VERSION capability bit the device reports
    /// clear (nothing is hidden before the device has answered CMD_VERSION); then those every
    /// device has.
    pub fn shown(&self, station: &Station) -> Vec<PanelId> {
        let mut v: Vec<PanelId> = station
            .panel_kinds()
            .into_iter()
            .filter_map(|kind| self.iter().find(|p| p.kind() == Some(kind)))
            .map(|p| p.id())
            .collect();
        v.extend(self.iter().filter(|p| p.kind().is_none()).map(|p| p.id()));
        v
    }

    /// Draws panel `id`; its actions, a job it starts marked as its own.
    pub fn show(&mut self, id: PanelId, ui: &mut egui::Ui, cx: &Cx<'_>) -> Vec<Action> {
        self.one(id, |p| p.show(ui, cx))
    }

    /// Every panel's tick.
    pub fn tick(&mut self, station: &Station) -> Vec<Action> {
        self.all(|p| p.tick(station))
    }

    /// Every panel forgets (see [`Panel::forget`]).
    pub fn forget(&mut self, station: &Station, why: Forget) -> Vec<Action> {
        self.all(|p| p.forget(station, why))
    }

    /// Hands `out` to panel `to`, which started the job.
    pub fn deliver(&mut self, to: PanelId, out: PanelOutput, station: &Station) -> Vec<Action> {
        self.one(to, |p| p.on_output(out, station))
    }

    /// Every panel takes its files from `settings`.
    pub fn restore(&mut self, settings: &Settings) {
        for p in &mut self.0 {
            p.restore(settings);
        }
    }

    /// Shows part `part` of panel `id`.
    pub fn show_part(&mut self, id: PanelId, part: usize, station: &Station) {
        self.one(id, |p| {
            p.show_part(part, station);
            Vec::new()
        });
    }

    /// Runs `f` on panel `id`; the jobs it asks to start are marked as that panel's, so that
    /// their output comes back to it.
    fn one(&mut self, id: PanelId, f: impl FnOnce(&mut dyn Panel) -> Vec<Action>) -> Vec<Action> {
        match self.0.iter_mut().find(|p| p.id() == id) {
            Some(p) => owned_by(id, f(p.as_mut())),
            None => Vec::new(),
        }
    }

    /// Runs `f` on every panel, as [`Self::one`] does.
    fn all(&mut self, mut f: impl FnMut(&mut dyn Panel) -> Vec<Action>) -> Vec<Action> {
        let mut actions = Vec::new();
        for p in &mut self.0 {
            let id = p.id();
            actions.extend(owned_by(id, f(p.as_mut())));
        }
        actions
    }
}

/// `actions`, each job in them marked as started by panel `id` (unless already marked).
fn owned_by(id: PanelId, actions: Vec<Action>) -> Vec<Action> {
    actions
        .into_iter()
        .map(|a| match a {
            Action::StartJob(job) => Action::StartJob(job.owned_by(id)),
            a => a,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panel_id_is_saved_as_the_enum_was_and_read_back() {
        assert_eq!(ron::to_string(&PanelId::SELF_TEST).unwrap(), "SelfTest");
        let back: PanelId = ron::from_str("SelfTest").unwrap();
        assert_eq!(back, PanelId::SELF_TEST);
        let saved: crate::ui::Settings = ron::from_str("(panel: ServoBench)").unwrap();
        assert_eq!(saved.panel, PanelId::SERVO_BENCH);
        let err = ron::from_str::<PanelId>("Nope").unwrap_err().to_string();
        assert!(err.contains("unknown panel 'Nope'"), "{err}");
    }

    #[test]
    fn every_panel_in_the_list_has_an_id_of_its_own_and_a_name_in_each_language() {
        let list = crate::ui::panels();
        let mut ids: Vec<&str> = list.iter().map(|p| p.id().as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), list.len(), "{ids:?}");
        for p in &list {
            for lang in Lang::ALL {
                assert!(!p.name(lang).is_empty(), "{}", p.id());
            }
            assert_eq!(PanelId::parse(p.id().as_str()), Some(p.id()));
        }
    }

    #[test]
    fn a_jobs_output_is_the_panels_own_type_or_nothing() {
        let out = PanelOutput::new(7u32);
        assert_eq!(out.take::<u32>(), Some(7));
        assert_eq!(PanelOutput::new("text").take::<u32>(), None);
    }
}
