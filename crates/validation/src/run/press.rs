//! The cases of the paper's press (docs/model.md §6): which joint joins rod and slider, the
//! crank speed and the radial clearance — the identity of a case, its file stem (the scene
//! `cases/press/STEM.json` and the `case` of its summary.json), its scene and the RK4 step the
//! engine runs it at.
//!
//! ```text
//! stem   = "ideal_" RPM "rpm"                                   ideal_150rpm
//!        | ("dry" | "lubricated") "_" RPM "rpm_c" C_MM          dry_150rpm_c0.1
//! RPM    a whole number of revolutions per minute; C_MM the radial clearance in mm, written
//!        as the shortest decimal of clearance_um / 1000 (0.1, 0.2, 0.3, 0.5)
//! scene  lash_model::cases::press_scene(joint, rpm, c), c = clearance_um / 10⁶ m
//!        (0 for the ideal joint): the scene of the catalogue, bit for bit
//! ```
//!
//! Source: docs/model.md §5–§6; `lash_model::cases` (the generator of cases/press).

use std::fmt;
use std::str::FromStr;

use lash_model::cases::{press_scene, PressJoint};
use lash_model::Scene;

/// The joint of a press case, between rod and slider.
///
/// ```text
/// Dry (IMPACT + Coulomb) | Lubricated (long Gümbel film + contact) | Ideal (pin)
/// ```
///
/// Source: docs/model.md §3–§5.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Dry clearance joint.
    Dry,
    /// Lubricated clearance joint.
    Lubricated,
    /// Ideal revolute joint.
    Ideal,
}

impl Kind {
    /// The word a file stem starts with.
    const fn word(self) -> &'static str {
        match self {
            Kind::Dry => "dry",
            Kind::Lubricated => "lubricated",
            Kind::Ideal => "ideal",
        }
    }
}

/// A case of the paper's press: joint, crank speed, radial clearance (module doc).
///
/// ```text
/// PressCase::dry(150, 100)  ⇔  "dry_150rpm_c0.1"      (rpm, clearance in µm)
/// PressCase::ideal(150)     ⇔  "ideal_150rpm"
/// ```
///
/// Source: docs/model.md §6.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PressCase {
    kind: Kind,
    rpm: u32,
    /// Radial clearance, µm (0 for the ideal joint).
    clearance_um: u32,
}

impl PressCase {
    /// A dry clearance joint at `rpm` with radial clearance `clearance_um` µm.
    pub(crate) const fn dry(rpm: u32, clearance_um: u32) -> PressCase {
        PressCase {
            kind: Kind::Dry,
            rpm,
            clearance_um,
        }
    }

    /// A lubricated clearance joint at `rpm` with radial clearance `clearance_um` µm.
    pub(crate) const fn lubricated(rpm: u32, clearance_um: u32) -> PressCase {
        PressCase {
            kind: Kind::Lubricated,
            rpm,
            clearance_um,
        }
    }

    /// The ideal joint at `rpm`.
    pub(crate) const fn ideal(rpm: u32) -> PressCase {
        PressCase {
            kind: Kind::Ideal,
            rpm,
            clearance_um: 0,
        }
    }

    /// The joint.
    pub(crate) fn kind(self) -> Kind {
        self.kind
    }

    /// The crank speed, rpm.
    pub(crate) fn rpm(self) -> f64 {
        f64::from(self.rpm)
    }

    /// The radial clearance, m (None for the ideal joint).
    pub(crate) fn clearance(self) -> Option<f64> {
        (self.kind != Kind::Ideal).then(|| f64::from(self.clearance_um) / 1e6)
    }

    /// The scene (the catalogue's, `lash_model::cases::press_catalogue`, bit for bit).
    pub(crate) fn scene(self) -> Scene {
        let joint = match self.kind {
            Kind::Dry => PressJoint::Dry,
            Kind::Lubricated => PressJoint::Lubricated,
            Kind::Ideal => PressJoint::Ideal,
        };
        press_scene(joint, self.rpm(), self.clearance().unwrap_or(0.0))
    }

    /// The fixed RK4 step the engine runs this case at, s: the largest step found stable that
    /// keeps the constraint violation ‖Φ‖ below 1e-8 over the case (the `rk4_scan` example
    /// of lash-model; its tests run every case with the same steps).
    ///
    /// ```text
    /// ideal 1e-3 s;  dry 2e-4 s;  lubricated: c = 0.1, 0.5 mm 2e-6 s, c = 0.3 mm 5e-7 s,
    /// c = 0.2 mm 2e-7 s (the film's radial damping grows as (1 − ε²)^{−3/2} up to
    /// ε_cap = 0.99, which bounds the RK4 step); other lubricated clearances 2e-6 s
    /// ```
    ///
    /// Source: the rk4_scan measurements (crates/model/tests/press_cases.rs checks ‖Φ‖);
    /// docs/model.md §9.
    pub fn rk4_step(self) -> f64 {
        match (self.kind, self.clearance_um) {
            (Kind::Ideal, _) => 1e-3,
            (Kind::Dry, _) => 2e-4,
            (Kind::Lubricated, 200) => 2e-7,
            (Kind::Lubricated, 300) => 5e-7,
            (Kind::Lubricated, _) => 2e-6,
        }
    }
}

impl fmt::Display for PressCase {
    /// The file stem (module doc).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}_{}rpm", self.kind.word(), self.rpm)?;
        if self.kind != Kind::Ideal {
            write!(f, "_c{}", f64::from(self.clearance_um) / 1000.0)?;
        }
        Ok(())
    }
}

/// A file stem that is not a press case's (the module doc gives the form).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not a press case (ideal_RPMrpm, dry_RPMrpm_cMM or lubricated_RPMrpm_cMM)")]
pub struct NotAPressCase(String);

impl FromStr for PressCase {
    type Err = NotAPressCase;

    /// Parses a file stem; the stem written back is the one parsed (`0.10` or `150.0rpm`
    /// are refused), so a stem names one case.
    fn from_str(stem: &str) -> Result<PressCase, NotAPressCase> {
        let bad = || NotAPressCase(stem.to_string());
        let (word, rest) = stem.split_once('_').ok_or_else(bad)?;
        let kind = [Kind::Dry, Kind::Lubricated, Kind::Ideal]
            .into_iter()
            .find(|k| k.word() == word)
            .ok_or_else(bad)?;
        let (rpm, clearance) = match rest.split_once("rpm") {
            Some((rpm, "")) if kind == Kind::Ideal => (rpm, None),
            Some((rpm, c)) if kind != Kind::Ideal => {
                (rpm, Some(c.strip_prefix("_c").ok_or_else(bad)?))
            }
            _ => return Err(bad()),
        };
        let rpm: u32 = rpm.parse().map_err(|_| bad())?;
        let clearance_um = match clearance {
            None => 0,
            Some(mm) => {
                let v: f64 = mm.parse().map_err(|_| bad())?;
                let um = (v * 1000.0).round();
                if !(um >= 1.0 && um <= f64::from(u32::MAX)) {
                    return Err(bad());
                }
                um as u32
            }
        };
        let case = PressCase {
            kind,
            rpm,
            clearance_um,
        };
        if rpm == 0 || case.to_string() != stem {
            return Err(bad());
        }
        Ok(case)
    }
}

/// Which runs of a press case a claim reads: the plan's runs, or the same realisations run
/// until the orbit settles (`run::steady`).
///
/// ```text
/// label = STEM (Runs) | STEM "@steady_state" (SteadyState)      (study.json's numbers)
/// ```
///
/// Source: the claims of `studies::paper` (P25 is judged at steady state).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Variant {
    /// The plan's runs (two revolutions).
    Runs,
    /// The runs until periodic.
    SteadyState,
}

/// The runs of one case in one variant: what a claim's number names.
///
/// Source: [`Variant`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct RunKey {
    /// The case.
    pub(crate) case: PressCase,
    /// Which of its runs.
    pub(crate) variant: Variant,
}

impl RunKey {
    /// The plan's runs of `case`.
    pub(crate) fn runs(case: PressCase) -> RunKey {
        RunKey {
            case,
            variant: Variant::Runs,
        }
    }

    /// The runs of `case` until periodic.
    pub(crate) fn steady_state(case: PressCase) -> RunKey {
        RunKey {
            case,
            variant: Variant::SteadyState,
        }
    }
}

impl fmt::Display for RunKey {
    /// The label of the runs in study.json's numbers (the type doc).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.variant {
            Variant::Runs => write!(f, "{}", self.case),
            Variant::SteadyState => write!(f, "{}@steady_state", self.case),
        }
    }
}

impl From<PressCase> for RunKey {
    fn from(case: PressCase) -> RunKey {
        RunKey::runs(case)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 18 cases of cases/press written by the model's generator.
    fn catalogue() -> Vec<(String, Scene)> {
        lash_model::cases::press_catalogue()
    }

    #[test]
    fn every_catalogue_stem_parses_back_to_itself_and_gives_its_scene_bit_for_bit() {
        let cat = catalogue();
        assert_eq!(cat.len(), 18);
        for (stem, scene) in &cat {
            let c: PressCase = stem.parse().unwrap();
            assert_eq!(&c.to_string(), stem);
            assert_eq!(&c.scene(), scene, "{stem}");
        }
        assert_eq!(PressCase::dry(150, 100), "dry_150rpm_c0.1".parse().unwrap());
        assert_eq!(PressCase::ideal(200).to_string(), "ideal_200rpm");
        assert_eq!(PressCase::lubricated(150, 300).clearance(), Some(3e-4));
        assert_eq!(PressCase::ideal(120).clearance(), None);
    }

    #[test]
    fn stems_that_name_no_case_are_refused() {
        for bad in [
            "",
            "dry",
            "dry_150rpm",
            "ideal_150rpm_c0.1",
            "dry_150rpm_c0.10",
            "dry_150.0rpm_c0.1",
            "dry_0rpm_c0.1",
            "dry_150rpm_c0",
            "dry_150rpm_c-0.1",
            "wet_150rpm_c0.1",
            "dry_150rpm_x0.1",
            "punch_motor_150rpm_c0.1",
        ] {
            let e = bad.parse::<PressCase>().unwrap_err();
            assert!(e.to_string().contains(&format!("'{bad}'")), "{e}");
        }
    }

    #[test]
    fn rk4_steps_are_the_scans_and_the_labels_name_the_variant() {
        // The steps of the rk4_scan (the model tests run every case with the same).
        let step = |s: &str| s.parse::<PressCase>().unwrap().rk4_step();
        assert_eq!(step("ideal_150rpm"), 1e-3);
        assert_eq!(step("dry_200rpm_c0.1"), 2e-4);
        assert_eq!(step("lubricated_150rpm_c0.1"), 2e-6);
        assert_eq!(step("lubricated_150rpm_c0.2"), 2e-7);
        assert_eq!(step("lubricated_150rpm_c0.3"), 5e-7);
        assert_eq!(step("lubricated_150rpm_c0.5"), 2e-6);
        let c = PressCase::lubricated(150, 200);
        assert_eq!(RunKey::runs(c).to_string(), "lubricated_150rpm_c0.2");
        assert_eq!(
            RunKey::steady_state(c).to_string(),
            "lubricated_150rpm_c0.2@steady_state"
        );
    }
}
