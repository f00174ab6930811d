//! The paper's qualitative claims of §4 (and the cross-checks of docs/model.md §5, §9), each turned
//! into a criterion on the measured statistics and decided from them.
//!
//! ```text
//! value(case, q)   = mean over the case's realisations of q          (the verdict)
//!                  = q of realisation k                               (robustness, k = 0..N)
//! verdict          = HOLDS if the criterion is true on the means, else DOES NOT HOLD
//! realisations     = #{k : criterion true on realisation k} of N
//! ```
//!
//! The dry cases are chaotic (docs/model.md §9): one revolution's maximum, RMS or count depends on
//! the realisation, so every case runs as an ensemble of realisations that differ only by a
//! micro-radian of initial crank phase, and the claims compare ensemble means. A case with one
//! realisation (the ideal mechanism, deterministic) takes part in every one.
//!
//! Thresholds, fixed for all claims: "little effect" on displacement = below 1 % of the stroke
//! 2r; "scarcely different" acceleration = max |ẍ − ẍ_ideal| below 1 % of the ideal peak;
//! "obvious" deviation = at least 5 % of the ideal peak; "fluctuation" in a 45° sector = max
//! |ẍ − ẍ_ideal| above 10 % of the ideal peak there; "near the boundary" = ε_max ≥ 0.9; "not
//! chaotic" = the realisations' pointwise acceleration spread below 0.1 % of the ideal peak;
//! "periodic" = the last revolution's orbit within 5 % of c of the previous one.
//!
//! Source: the paper's §4 (quoted per claim), docs/model.md §5 and §9.

use std::cell::RefCell;
use std::collections::BTreeMap;

use crate::error::Error;
use crate::run::press::{PressCase, RunKey};
use crate::studies::paper::plan::CLEARANCES_MM;
use crate::studies::paper::plan::DRY_CLEARANCES;
use crate::studies::paper::plan::DRY_SPEEDS;
use crate::studies::paper::plan::IDEALS;
use crate::studies::paper::plan::LUB_CLEARANCES;
use crate::studies::paper::plan::LUB_SPEEDS;
use crate::studies::paper::stats::{CaseStats, Ensemble};

/// "Little effect" on the displacement: below this fraction of the stroke 2r.
pub(crate) const LITTLE: f64 = 0.01;
/// "Scarcely different" acceleration: max deviation below this fraction of the ideal peak.
pub(crate) const SCARCELY: f64 = 0.01;
/// "Obvious" acceleration deviation: max deviation at least this fraction of the ideal peak.
pub(crate) const OBVIOUS: f64 = 0.05;
/// "Near the boundary" of the clearance circle: ε_max at least this.
pub(crate) const NEAR_BOUNDARY: f64 = 0.9;
/// "Not chaotic": the realisations' pointwise acceleration spread below this fraction of the
/// ideal peak.
pub(crate) const NOT_CHAOTIC: f64 = 1e-3;
/// "Periodic": max |e_k − e_{k−1}| / c between the last two revolutions below this.
pub(crate) const PERIODIC: f64 = 0.05;
/// "Grows markedly" (P16): the RMS deviation at 0.5 mm at least this multiple of that at
/// 0.3 mm.
pub(crate) const MARKED_GROWTH: f64 = 1.25;

/// The thresholds the claims are judged with (the module doc says what each means).
///
/// ```text
/// little 0.01 of the stroke, scarcely 0.01 and obvious 0.05 of the ideal peak, near the
/// boundary ε ≥ 0.9, not chaotic spread < 1e-3 of the peak, periodic closure < 0.05 c,
/// marked growth × 1.25
/// ```
///
/// The 10 % of a "fluctuating" sector (`stats::SECTOR_FLUCTUATION`) is applied when the
/// runs' statistics are made, not here.
///
/// Source: this module (the constants above).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Thresholds {
    /// [`LITTLE`].
    pub little: f64,
    /// [`SCARCELY`].
    pub scarcely: f64,
    /// [`OBVIOUS`].
    pub obvious: f64,
    /// [`NEAR_BOUNDARY`].
    pub near_boundary: f64,
    /// [`NOT_CHAOTIC`].
    pub not_chaotic: f64,
    /// [`PERIODIC`].
    pub periodic: f64,
    /// [`MARKED_GROWTH`].
    pub marked_growth: f64,
}

impl Thresholds {
    /// The study's thresholds (the constants of this module).
    pub(crate) fn paper() -> Thresholds {
        Thresholds {
            little: LITTLE,
            scarcely: SCARCELY,
            obvious: OBVIOUS,
            near_boundary: NEAR_BOUNDARY,
            not_chaotic: NOT_CHAOTIC,
            periodic: PERIODIC,
            marked_growth: MARKED_GROWTH,
        }
    }
}

/// A statistic of one realisation of one case that a claim reads.
///
/// ```text
/// metrics of docs/outputs.md (slider_acc_rms_dev_ideal, eps_max, ...) and the study's deviations
/// (x_dev_max = max |x − x_ideal|, ...); acc_spread = max_i (max_k ẍ_k,i − min_k ẍ_k,i)
/// ```
///
/// Source: docs/outputs.md (`metrics`); this module's [`super::Deviations`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Quantity {
    /// `slider_acc_rms_dev_ideal`, m/s².
    RmsDev,
    /// `eps_max`.
    EpsMax,
    /// `penetration_max`, m.
    PenetrationMax,
    /// `contact_force_max`, N.
    ContactForceMax,
    /// Stroke max x_ideal − min x_ideal, m.
    Stroke,
    /// max |x − x_ideal|, m.
    XDevMax,
    /// max |ẋ − ẋ_ideal|, m/s.
    VDevMax,
    /// max |ẍ − ẍ_ideal|, m/s².
    ADevMax,
    /// max |ẍ_ideal|, m/s².
    AIdealPeak,
    /// max |x − x_ideal| within ±15° of the bottom dead centre θ ≡ 0, m.
    XDevBdc,
    /// max |ẍ − ẍ_ideal| within ±15° of θ ≡ 0 or π, m/s².
    ADevDeadCentres,
    /// RMS(x − x_ideal) / RMS(x_ideal − mean x_ideal).
    XDevRel,
    /// RMS(ẋ − ẋ_ideal) / RMS(ẋ_ideal − mean ẋ_ideal).
    VDevRel,
    /// RMS(ẍ − ẍ_ideal) / RMS(ẍ_ideal − mean ẍ_ideal).
    ADevRel,
    /// Number of 45° sectors of the revolution whose max |ẍ − ẍ_ideal| exceeds 10 % of the
    /// ideal peak.
    FluctuationSectors,
    /// Fraction of the grid with δ > 0 (journal in contact).
    ContactFraction,
    /// max |e(t) − e(t − T)| / c over the last revolution.
    OrbitClosure,
    /// The ensemble's pointwise acceleration spread, m/s² (one value per case).
    AccSpread,
}

impl Quantity {
    /// Name in the report and study.json.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Quantity::RmsDev => "slider_acc_rms_dev_ideal",
            Quantity::EpsMax => "eps_max",
            Quantity::PenetrationMax => "penetration_max",
            Quantity::ContactForceMax => "contact_force_max",
            Quantity::Stroke => "stroke",
            Quantity::XDevMax => "x_dev_max",
            Quantity::VDevMax => "v_dev_max",
            Quantity::ADevMax => "a_dev_max",
            Quantity::AIdealPeak => "a_ideal_peak",
            Quantity::XDevBdc => "x_dev_bdc",
            Quantity::ADevDeadCentres => "a_dev_dead_centres",
            Quantity::XDevRel => "x_dev_rel",
            Quantity::VDevRel => "v_dev_rel",
            Quantity::ADevRel => "a_dev_rel",
            Quantity::FluctuationSectors => "fluctuation_sectors",
            Quantity::ContactFraction => "contact_fraction",
            Quantity::OrbitClosure => "orbit_closure",
            Quantity::AccSpread => "acc_spread",
        }
    }

    /// The value for one realisation (None when the case lacks it, e.g. ε of the ideal one).
    pub(crate) fn of(self, s: &CaseStats) -> Option<f64> {
        let (m, d) = (&s.metrics, &s.dev);
        match self {
            Quantity::RmsDev => m.slider_acc_rms_dev_ideal,
            Quantity::EpsMax => m.eps_max,
            Quantity::PenetrationMax => m.penetration_max,
            Quantity::ContactForceMax => m.contact_force_max,
            Quantity::Stroke => Some(d.stroke),
            Quantity::XDevMax => Some(d.x_dev_max),
            Quantity::VDevMax => Some(d.v_dev_max),
            Quantity::ADevMax => Some(d.a_dev_max),
            Quantity::AIdealPeak => Some(d.a_ideal_peak),
            Quantity::XDevBdc => Some(d.x_dev_bdc),
            Quantity::ADevDeadCentres => Some(d.a_dev_dead_centres),
            Quantity::XDevRel => Some(d.x_dev_rel),
            Quantity::VDevRel => Some(d.v_dev_rel),
            Quantity::ADevRel => Some(d.a_dev_rel),
            Quantity::FluctuationSectors => Some(d.fluctuation_sectors as f64),
            Quantity::ContactFraction => d.contact_fraction,
            Quantity::OrbitClosure => d.orbit_closure,
            Quantity::AccSpread => None,
        }
    }
}

/// The verdict on a claim.
///
/// ```text
/// HOLDS ⇔ criterion(ensemble means) is true;  DOES NOT HOLD otherwise
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Verdict {
    /// The criterion is met.
    #[serde(rename = "HOLDS")]
    Holds,
    /// The criterion is not met.
    #[serde(rename = "DOES NOT HOLD")]
    DoesNotHold,
}

impl Verdict {
    /// HOLDS for true.
    pub(crate) fn of(b: bool) -> Verdict {
        if b {
            Verdict::Holds
        } else {
            Verdict::DoesNotHold
        }
    }
    /// "HOLDS" or "DOES NOT HOLD".
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Verdict::Holds => "HOLDS",
            Verdict::DoesNotHold => "DOES NOT HOLD",
        }
    }
}

/// Where a claim comes from.
///
/// ```text
/// Paper = a sentence of the paper's §4;  Model = a statement of docs/model.md (§5, §9)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The paper's §4.
    Paper,
    /// A statement of docs/model.md (§5, §9).
    Model,
}

/// One number a verdict rests on.
///
/// ```text
/// value = ensemble mean (or a value derived from means);  [min, max] over the realisations
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Number {
    /// `CASE quantity` or a derived quantity's description.
    pub label: String,
    /// The value (ensemble mean for a case quantity).
    pub value: f64,
    /// Smallest value over the realisations (case quantities with several realisations).
    pub min: Option<f64>,
    /// Largest value over the realisations.
    pub max: Option<f64>,
}

/// A claim checked against the runs.
///
/// ```text
/// statement, quoted source, criterion → numbers → verdict; realisations_holding of realisations
/// ```
///
/// Source: the paper's §4 (quoted in `source`) or docs/model.md §5, §9.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Claim {
    /// Identifier (P1, P2, ... paper; M1, ... docs/model.md §5, §9).
    pub id: String,
    /// Paper or docs/model.md.
    pub origin: Origin,
    /// The figure(s) the claim is about.
    pub figure: String,
    /// The claim in one sentence.
    pub statement: String,
    /// The quoted source sentence(s).
    pub source: String,
    /// The measurable criterion.
    pub criterion: String,
    /// A caveat on reading the verdict (empty if none).
    pub note: String,
    /// The numbers the verdict rests on.
    pub numbers: Vec<Number>,
    /// The verdict on the ensemble means.
    pub verdict: Verdict,
    /// Relative margin of the verdict on the means: the smallest (b − a)/max(|a|, |b|) over
    /// the criterion's comparisons a < b (or a ≤ b); ≥ 0 when the claim holds (0: on the
    /// threshold of an "at least"), ≤ 0 when it does not (the comparison that fails by most).
    #[serde(default)]
    pub margin: f64,
    /// Realisations on which the criterion is true.
    pub realisations_holding: usize,
    /// Number of realisations.
    pub realisations: usize,
}

/// The runs of each case (its plan's runs, and its runs until periodic where it has them).
///
/// ```text
/// (case, variant) → Ensemble { members[k] = statistics of realisation k, acc_spread }
/// ```
///
/// Source: `stats::Ensemble`; `run::press::RunKey`.
pub(crate) type Cases = BTreeMap<RunKey, Ensemble>;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Pick {
    Mean,
    Member(usize),
}

/// What a criterion sees: the statistics of the ensemble means or of one realisation; logs
/// the numbers it reads (means only).
struct View<'a> {
    cases: &'a Cases,
    pick: Pick,
    log: RefCell<Vec<Number>>,
    th: &'a Thresholds,
    /// Relative margins of the comparisons made (see [`Claim::margin`]).
    margins: RefCell<Vec<f64>>,
}

/// Relative margin of a < b (or a ≤ b): (b − a)/max(|a|, |b|); 0 when both are 0.
fn relative_margin(a: f64, b: f64) -> f64 {
    let scale = a.abs().max(b.abs());
    if scale > 0.0 {
        (b - a) / scale
    } else {
        0.0
    }
}

impl View<'_> {
    /// a < b, its margin recorded.
    fn less(&self, a: f64, b: f64) -> bool {
        self.margins.borrow_mut().push(relative_margin(a, b));
        a < b
    }

    /// a ≥ b, its margin recorded.
    fn at_least(&self, a: f64, b: f64) -> bool {
        self.margins.borrow_mut().push(relative_margin(b, a));
        a >= b
    }

    /// Every element above the one before it, margins recorded.
    fn increasing(&self, v: &[f64]) -> bool {
        let mut ok = true;
        for w in v.windows(2) {
            ok &= self.less(w[0], w[1]);
        }
        ok
    }

    /// a[i] < b[i] for every i, margins recorded.
    fn below(&self, a: &[f64], b: &[f64]) -> bool {
        let mut ok = true;
        for (x, y) in a.iter().zip(b) {
            ok &= self.less(*x, *y);
        }
        ok
    }

    /// The case's runs until periodic when there are any, else its own runs.
    fn periodic_case(&self, case: PressCase) -> RunKey {
        let s = RunKey::steady_state(case);
        if self.cases.contains_key(&s) {
            s
        } else {
            RunKey::runs(case)
        }
    }

    fn get(&self, case: impl Into<RunKey>, q: Quantity) -> Result<f64, Error> {
        let case: RunKey = case.into();
        let e = self
            .cases
            .get(&case)
            .ok_or_else(|| Error::Internal(format!("study: no runs of case {case}")))?;
        if e.members.is_empty() {
            return Err(Error::Internal(format!("study: case {case} has no runs")));
        }
        let label = format!("{case} {}", q.name());
        let (value, range) = if q == Quantity::AccSpread {
            (e.acc_spread, None)
        } else {
            let vals: Vec<f64> = e
                .members
                .iter()
                .map(|m| {
                    q.of(m).ok_or_else(|| {
                        Error::Internal(format!("study: case {case} has no {}", q.name()))
                    })
                })
                .collect::<Result<_, _>>()?;
            match self.pick {
                Pick::Mean => {
                    let mean = vals.iter().sum::<f64>() / vals.len() as f64;
                    let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    (mean, (vals.len() > 1).then_some((lo, hi)))
                }
                Pick::Member(k) => (vals[k % vals.len()], None),
            }
        };
        if !value.is_finite() {
            return Err(Error::Internal(format!("study: {label} is {value}")));
        }
        if self.pick == Pick::Mean {
            let mut log = self.log.borrow_mut();
            if !log.iter().any(|n| n.label == label) {
                log.push(Number {
                    label,
                    value,
                    min: range.map(|r| r.0),
                    max: range.map(|r| r.1),
                });
            }
        }
        Ok(value)
    }

    fn all(&self, cases: &[PressCase], q: Quantity) -> Result<Vec<f64>, Error> {
        cases.iter().map(|&c| self.get(c, q)).collect()
    }

    /// Records a derived number (ratio, threshold) in the mean view.
    fn note(&self, label: impl Into<String>, value: f64) {
        if self.pick == Pick::Mean {
            self.log.borrow_mut().push(Number {
                label: label.into(),
                value,
                min: None,
                max: None,
            });
        }
    }
}

fn span(v: &[f64]) -> f64 {
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    hi - lo
}

type Criterion = fn(&View<'_>) -> Result<bool, Error>;

struct Def {
    id: &'static str,
    origin: Origin,
    figure: &'static str,
    statement: &'static str,
    source: &'static str,
    criterion: &'static str,
    note: &'static str,
    eval: Criterion,
}

/// Every claim, in the order of the paper's text.
const DEFS: &[Def] = &[
    Def {
        id: "P1",
        origin: Origin::Paper,
        figure: "Fig. 5(a)",
        statement: "Dry, 120–200 rpm: the clearance joint has little effect on the slider displacement.",
        source: "The position trajectory of the slider, from a macroeconomic point of view, retains smooth characteristics, and the clearance joint has little effect on slider displacement.",
        criterion: "max |x − x_ideal| < 1 % of the stroke 2r at every speed (dry, 0.1 mm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in DRY_SPEEDS {
                ok &= v.less(
                    v.get(c, Quantity::XDevMax)?,
                    v.th.little * v.get(c, Quantity::Stroke)?,
                );
            }
            Ok(ok)
        },
    },
    Def {
        id: "P2",
        origin: Origin::Paper,
        figure: "Fig. 5(a)",
        statement: "Dry: the drift of the bottom dead point grows with the rotation speed.",
        source: "However, the inertial force of the slider due to rotation speed changes the motion contour of the slider in the extreme position, and the drift phenomenon of the bottom dead point can occur.",
        criterion: "max |x − x_ideal| within ±15° of the bottom dead centre (θ ≡ 0, slider farthest from the crank) strictly increases with speed (dry, 0.1 mm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_SPEEDS, Quantity::XDevBdc)?)),
    },
    Def {
        id: "P3",
        origin: Origin::Paper,
        figure: "Fig. 5, 6",
        statement: "Dry: the acceleration is more sensitive to the clearance than displacement and velocity.",
        source: "Compared with the displacement and velocity of the slider, the acceleration is more sensitive to variations in working conditions.",
        criterion: "At every speed the relative RMS deviation from the ideal, RMS(q − q_ideal)/RMS(q_ideal − mean), is larger for q = ẍ than for q = x and q = ẋ (dry, 0.1 mm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in DRY_SPEEDS {
                let a = v.get(c, Quantity::ADevRel)?;
                ok &= v.less(v.get(c, Quantity::XDevRel)?, a) & v.less(v.get(c, Quantity::VDevRel)?, a);
            }
            Ok(ok)
        },
    },
    Def {
        id: "P4",
        origin: Origin::Paper,
        figure: "Fig. 6",
        statement: "Dry: the acceleration fluctuates over the whole revolution.",
        source: "The noticeable fluctuation of the mechanism with the clearance joint is found in the whole motion period.",
        criterion: "In all eight 45° sectors of the revolution max |ẍ − ẍ_ideal| exceeds 10 % of the ideal peak, at every speed (dry, 0.1 mm; the mean over realisations must be 8).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in DRY_SPEEDS {
                ok &= v.at_least(v.get(c, Quantity::FluctuationSectors)?, 8.0);
            }
            Ok(ok)
        },
    },
    Def {
        id: "P5",
        origin: Origin::Paper,
        figure: "Fig. 6",
        statement: "Dry: the acceleration fluctuation grows with the rotation speed.",
        source: "With the increase in rotation speed, the vibration characteristics become more complex and the peak value of fluctuation in the extreme position is improved.",
        criterion: "slider_acc_rms_dev_ideal strictly increases from 120 to 150 to 180 to 200 rpm (dry, 0.1 mm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_SPEEDS, Quantity::RmsDev)?)),
    },
    Def {
        id: "P6",
        origin: Origin::Paper,
        figure: "Fig. 6",
        statement: "Dry: the peak fluctuation at the extreme positions grows with the rotation speed.",
        source: "With the increase in rotation speed, the vibration characteristics become more complex and the peak value of fluctuation in the extreme position is improved.",
        criterion: "max |ẍ − ẍ_ideal| within ±15° of the dead centres (θ ≡ 0 or π) strictly increases with speed (dry, 0.1 mm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_SPEEDS, Quantity::ADevDeadCentres)?)),
    },
    Def {
        id: "P7",
        origin: Origin::Paper,
        figure: "Fig. 7",
        statement: "Dry: the journal moves freely at low speed; contact becomes more frequent as the speed rises.",
        source: "The free movement of the revolute joint is observed at a lower rotation speed. In the condition where n = 180 rpm, the rate of the contact phenomenon in the motion trajectory becomes active.",
        criterion: "The fraction of the revolution in contact (δ > 0) strictly increases with speed (dry, 0.1 mm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_SPEEDS, Quantity::ContactFraction)?)),
    },
    Def {
        id: "P8",
        origin: Origin::Paper,
        figure: "Fig. 7",
        statement: "Dry: the penetration grows with the speed and is largest at 200 rpm.",
        source: "However, the penetration characteristics are obvious when the rotation speed reaches 200 rpm, and the transmission time of the motion state (contact and impact) is also clear.",
        criterion: "penetration_max strictly increases with speed (dry, 0.1 mm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_SPEEDS, Quantity::PenetrationMax)?)),
    },
    Def {
        id: "P9",
        origin: Origin::Paper,
        figure: "Fig. 8, 9",
        statement: "Lubrication lowers the slider-acceleration fluctuation at every speed.",
        source: "It is obvious that the lubrication relieves the vibration feature effectively.",
        criterion: "slider_acc_rms_dev_ideal lubricated < dry at 120, 150, 180 and 200 rpm (0.1 mm).",
        note: "",
        eval: |v| {
            Ok(v.below(
                &v.all(&LUB_SPEEDS, Quantity::RmsDev)?,
                &v.all(&DRY_SPEEDS, Quantity::RmsDev)?,
            ))
        },
    },
    Def {
        id: "P10",
        origin: Origin::Paper,
        figure: "Fig. 8(a)",
        statement: "Lubricated: the bottom-dead-point drift is smaller than dry at every speed.",
        source: "The drift phenomenon of the bottom dead point is almost impossible to find in the slider displacement, and the slider velocity has a smoother transition in the extreme position.",
        criterion: "max |x − x_ideal| within ±15° of the bottom dead centre, lubricated < dry at every speed (0.1 mm).",
        note: "",
        eval: |v| {
            Ok(v.below(
                &v.all(&LUB_SPEEDS, Quantity::XDevBdc)?,
                &v.all(&DRY_SPEEDS, Quantity::XDevBdc)?,
            ))
        },
    },
    Def {
        id: "P11",
        origin: Origin::Paper,
        figure: "Fig. 8(b)",
        statement: "Lubricated: the slider velocity deviates less from the ideal than dry at every speed.",
        source: "The drift phenomenon of the bottom dead point is almost impossible to find in the slider displacement, and the slider velocity has a smoother transition in the extreme position.",
        criterion: "max |ẋ − ẋ_ideal|, lubricated < dry at every speed (0.1 mm).",
        note: "",
        eval: |v| {
            Ok(v.below(
                &v.all(&LUB_SPEEDS, Quantity::VDevMax)?,
                &v.all(&DRY_SPEEDS, Quantity::VDevMax)?,
            ))
        },
    },
    Def {
        id: "P12",
        origin: Origin::Paper,
        figure: "Fig. 9(d)",
        statement: "Lubricated, even at 200 rpm: the slider acceleration is scarcely different from the ideal joint's.",
        source: "Although the rotation speed is 200 rpm, the slider acceleration maintains a better dynamic response throughout the whole motion period, which is scarcely different from that of the ideal joint.",
        criterion: "max |ẍ − ẍ_ideal| < 1 % of the ideal peak |ẍ| at every speed (lubricated, 0.1 mm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in LUB_SPEEDS {
                ok &= v.less(
                    v.get(c, Quantity::ADevMax)?,
                    v.th.scarcely * v.get(c, Quantity::AIdealPeak)?,
                );
            }
            Ok(ok)
        },
    },
    Def {
        id: "P13",
        origin: Origin::Paper,
        figure: "Fig. 10",
        statement: "Lubricated, 120–200 rpm: the film keeps the journal off the bearing (orbit inside the clearance circle).",
        source: "The squeeze force of the oil film compensates for the clearance size, and the deviation value between the journal center and the bearing center is controlled. Free movement is the main motion state of slider crank mechanism during the whole period",
        criterion: "eps_max < 1 at every speed (lubricated, 0.1 mm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for e in v.all(&LUB_SPEEDS, Quantity::EpsMax)? {
                ok &= v.less(e, 1.0);
            }
            Ok(ok)
        },
    },
    Def {
        id: "P14",
        origin: Origin::Paper,
        figure: "Fig. 11(a)",
        statement: "Dry, 150 rpm: the displacement deviation grows with the clearance, more than it varies with the speed.",
        source: "Compared with the working condition effects, the degree of coincidence of the slider displacement with different clearance sizes cannot be found. The obvious deviation appears in the motion trajectory of the slider, which means that the expected route is changed by the clearance.",
        criterion: "max |x − x_ideal| strictly increases with the clearance (dry, 150 rpm), and its range over the four clearances exceeds its range over the four speeds (dry, 0.1 mm).",
        note: "",
        eval: |v| {
            let c = v.all(&DRY_CLEARANCES, Quantity::XDevMax)?;
            let s = v.all(&DRY_SPEEDS, Quantity::XDevMax)?;
            v.note("range of x_dev_max over the clearances, m", span(&c));
            v.note("range of x_dev_max over the speeds, m", span(&s));
            Ok(v.increasing(&c) & v.less(span(&s), span(&c)))
        },
    },
    Def {
        id: "P15",
        origin: Origin::Paper,
        figure: "Fig. 11(b)",
        statement: "Dry, 150 rpm: the velocity deviation grows with the clearance.",
        source: "The slider velocity could reflect this phenomenon clearly, as well as the intense vibration in the bottom point of the slider velocity.",
        criterion: "max |ẋ − ẋ_ideal| strictly increases with the clearance (dry, 150 rpm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_CLEARANCES, Quantity::VDevMax)?)),
    },
    Def {
        id: "P16",
        origin: Origin::Paper,
        figure: "Fig. 12",
        statement: "Dry, 150 rpm: beyond 0.3 mm clearance the acceleration fluctuation grows markedly.",
        source: "Notably, when the clearance size exceeds 0.3 mm, the contact phenomenon and vibration characteristics experience significant growth throughout the whole motion period.",
        criterion: "slider_acc_rms_dev_ideal at 0.5 mm ≥ 1.25 × that at 0.3 mm, and its growth per mm of clearance from 0.3 to 0.5 mm exceeds that from 0.1 to 0.3 mm (dry, 150 rpm).",
        note: "",
        eval: |v| {
            let r = v.all(&DRY_CLEARANCES, Quantity::RmsDev)?;
            let ratio = r[3] / r[2];
            let slope_hi = (r[3] - r[2]) / (CLEARANCES_MM[3] - CLEARANCES_MM[2]);
            let slope_lo = (r[2] - r[0]) / (CLEARANCES_MM[2] - CLEARANCES_MM[0]);
            v.note("RMS(0.5 mm) / RMS(0.3 mm)", ratio);
            v.note("growth 0.3→0.5 mm, m/s² per mm", slope_hi);
            v.note("growth 0.1→0.3 mm, m/s² per mm", slope_lo);
            Ok(v.at_least(ratio, v.th.marked_growth) & v.less(slope_lo, slope_hi))
        },
    },
    Def {
        id: "P17",
        origin: Origin::Paper,
        figure: "Fig. 13",
        statement: "Dry, 150 rpm: beyond 0.2 mm the journal moves freely (out of contact) clearly more.",
        source: "Beyond a clearance size of 0.2 mm, the free movement state is obviously enhanced. The results show that the activity of the clearance joint is improved in the larger clearance size condition.",
        criterion: "The contact fraction (δ > 0) at 0.3 and 0.5 mm is below its value at both 0.1 and 0.2 mm (dry, 150 rpm).",
        note: "",
        eval: |v| {
            let f = v.all(&DRY_CLEARANCES, Quantity::ContactFraction)?;
            Ok(v.less(f[2].max(f[3]), f[0].min(f[1])))
        },
    },
    Def {
        id: "P18",
        origin: Origin::Paper,
        figure: "Fig. 13",
        statement: "Dry, 150 rpm: the penetration grows with the clearance.",
        source: "Additionally, the penetration value of the contact impact is also enlarged.",
        criterion: "penetration_max strictly increases with the clearance (dry, 150 rpm).",
        note: "",
        eval: |v| Ok(v.increasing(&v.all(&DRY_CLEARANCES, Quantity::PenetrationMax)?)),
    },
    Def {
        id: "P19",
        origin: Origin::Paper,
        figure: "Fig. 14(a)",
        statement: "150 rpm: lubrication lowers the displacement deviation at every clearance.",
        source: "The deviation in the slider displacement can be decreased for the different clearance sizes, which also suggests that the motion range would be controlled.",
        criterion: "max |x − x_ideal|, lubricated < dry at 0.1, 0.2, 0.3 and 0.5 mm.",
        note: "",
        eval: |v| {
            Ok(v.below(
                &v.all(&LUB_CLEARANCES, Quantity::XDevMax)?,
                &v.all(&DRY_CLEARANCES, Quantity::XDevMax)?,
            ))
        },
    },
    Def {
        id: "P20",
        origin: Origin::Paper,
        figure: "Fig. 14(b), 15",
        statement: "150 rpm: lubrication restrains the velocity and acceleration fluctuation at every clearance.",
        source: "Then, the fluctuation in slider velocity and acceleration is restrained by the lubrication medium.",
        criterion: "max |ẋ − ẋ_ideal| and slider_acc_rms_dev_ideal, lubricated < dry at every clearance.",
        note: "",
        eval: |v| {
            Ok(v.below(
                &v.all(&LUB_CLEARANCES, Quantity::VDevMax)?,
                &v.all(&DRY_CLEARANCES, Quantity::VDevMax)?,
            ) & v.below(
                &v.all(&LUB_CLEARANCES, Quantity::RmsDev)?,
                &v.all(&DRY_CLEARANCES, Quantity::RmsDev)?,
            ))
        },
    },
    Def {
        id: "P21",
        origin: Origin::Paper,
        figure: "Fig. 15(d)",
        statement: "Lubricated, 150 rpm: at the largest clearance (0.5 mm) the acceleration deviates obviously from the ideal.",
        source: "However, the obvious deviation in slider acceleration is found in the larger clearance size (0.5 mm), which means unpredictable motion trajectory of the mechanism at the larger clearance size.",
        criterion: "At 0.5 mm max |ẍ − ẍ_ideal| ≥ 5 % of the ideal peak, and it is the largest of the four clearances (lubricated, 150 rpm).",
        note: "",
        eval: |v| {
            let d = v.all(&LUB_CLEARANCES, Quantity::ADevMax)?;
            let peak = v.get(LUB_CLEARANCES[3], Quantity::AIdealPeak)?;
            let mut ok = v.at_least(d[3], v.th.obvious * peak);
            for &x in &d[..3] {
                ok &= v.less(x, d[3]);
            }
            Ok(ok)
        },
    },
    Def {
        id: "P22",
        origin: Origin::Paper,
        figure: "Fig. 16",
        statement: "Lubricated, 150 rpm: only beyond 0.3 mm does the orbit reach the boundary of the clearance circle.",
        source: "When the clearance size exceeds 0.3 mm, the motion trajectory moves to the boundary outline.",
        criterion: "eps_max ≥ 0.9 at 0.5 mm, and eps_max < 0.9 at 0.1 and 0.2 mm (lubricated, 150 rpm).",
        note: "",
        eval: |v| {
            let e = v.all(&LUB_CLEARANCES, Quantity::EpsMax)?;
            let near = v.th.near_boundary;
            Ok(v.at_least(e[3], near) & v.less(e[0], near) & v.less(e[1], near))
        },
    },
    Def {
        id: "P23",
        origin: Origin::Paper,
        figure: "Fig. 16",
        statement: "Lubricated, 150 rpm: the oil film keeps the orbit inside the clearance circle at every clearance.",
        source: "The liquid medium is filled with the movement space of the clearance joint, and the eccentricity of the joint element centers extrudes the oil film, which is the reason why the supporting force of the lubricant medium appears.",
        criterion: "eps_max < 1 at 0.1, 0.2, 0.3 and 0.5 mm (lubricated, 150 rpm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for e in v.all(&LUB_CLEARANCES, Quantity::EpsMax)? {
                ok &= v.less(e, 1.0);
            }
            Ok(ok)
        },
    },
    Def {
        id: "P24",
        origin: Origin::Paper,
        figure: "Fig. 16",
        statement: "Lubricated, 150 rpm: the motion is not chaotic at any clearance.",
        source: "Although the motion range increases, the motion trajectory of the slider crank mechanism cannot be chaotic.",
        criterion: "The realisations' pointwise spread of ẍ over the last revolution is below 0.1 % of the ideal peak at every clearance (lubricated, 150 rpm).",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in LUB_CLEARANCES {
                ok &= v.less(
                    v.get(c, Quantity::AccSpread)?,
                    v.th.not_chaotic * v.get(c, Quantity::AIdealPeak)?,
                );
            }
            Ok(ok)
        },
    },
    Def {
        id: "P25",
        origin: Origin::Paper,
        figure: "Fig. 16",
        statement: "Lubricated, 150 rpm: the orbit is periodic at every clearance.",
        source: "Then, the regularity and periodicity of motion are presented.",
        criterion: "max |e(t) − e(t − T)| / c over the last revolution < 0.05 at every clearance (lubricated, 150 rpm), judged at steady state: each realisation runs until its once-per-revolution section moves by less than 0.01 c (at most 40 revolutions).",
        note: "The journal starts centred (docs/model.md §6) and sinks into the film over many revolutions; after two revolutions the gap is a transient that has not settled, which is why the claim is judged at steady state.",
        eval: |v| {
            let cases: Vec<RunKey> = LUB_CLEARANCES.iter().map(|&c| v.periodic_case(c)).collect();
            let mut ok = true;
            for &c in &cases {
                ok &= v.less(v.get(c, Quantity::OrbitClosure)?, v.th.periodic);
            }
            Ok(ok)
        },
    },
    Def {
        id: "M1",
        origin: Origin::Model,
        figure: "—",
        statement: "The ideal mechanism's runs reproduce the closed-form slider acceleration.",
        source: "Without clearance, the slider obeys the closed form (crank angle θ = ωt, S = sqrt(l² − r² sin²θ)) (docs/model.md §5)",
        criterion: "slider_acc_rms_dev_ideal < 1e-6 × the ideal peak for the four ideal runs.",
        note: "",
        eval: |v| {
            let mut ok = true;
            for c in IDEALS {
                ok &= v.less(
                    v.get(c, Quantity::RmsDev)?,
                    1e-6 * v.get(c, Quantity::AIdealPeak)?,
                );
            }
            Ok(ok)
        },
    },
    Def {
        id: "M2",
        origin: Origin::Model,
        figure: "Fig. 7(b)",
        statement: "Dry, 150 rpm, 0.1 mm: contact penetrates deeper than the clearance (|e|/c above 2, contact force above 30 kN).",
        source: "With the paper's soft K = 2.34e10 N/m^1.5 and the heavy slider, dry contact penetrates deeper than the clearance itself at 150 rpm, 0.1 mm (|e|/c above 2, contact force above 30 kN) (docs/model.md §9)",
        criterion: "eps_max > 2 and contact_force_max > 3e4 N (dry_150rpm_c0.1).",
        note: "",
        eval: |v| {
            Ok(v.less(2.0, v.get(DRY_SPEEDS[1], Quantity::EpsMax)?)
                & v.less(3e4, v.get(DRY_SPEEDS[1], Quantity::ContactForceMax)?))
        },
    },
    Def {
        id: "M3",
        origin: Origin::Model,
        figure: "Fig. 9(b), 10(b)",
        statement: "Lubricated, 150 rpm, 0.1 mm: the journal never touches the bearing and ẍ stays within about 1e-3 m/s² RMS of the ideal.",
        source: "With the film of §6, the lubricated 150 rpm, 0.1 mm journal never touches the bearing; its slider acceleration stays within about 1e-3 m/s² RMS of the ideal mechanism (docs/model.md §9)",
        criterion: "eps_max < 1 and slider_acc_rms_dev_ideal < 2e-3 m/s² (lubricated_150rpm_c0.1).",
        note: "",
        eval: |v| {
            Ok(v.less(v.get(LUB_SPEEDS[1], Quantity::EpsMax)?, 1.0)
                & v.less(v.get(LUB_SPEEDS[1], Quantity::RmsDev)?, 2e-3))
        },
    },
    Def {
        id: "M4",
        origin: Origin::Model,
        figure: "Fig. 6(b)",
        statement: "Dry, 150 rpm, 0.1 mm is chaotic: micro-radian changes of the initial crank phase change the second revolution's acceleration visibly.",
        source: "The dry cases are chaotic. At 150 rpm with 0.1 mm clearance, moving the slider's initial position by 1e-15 m changes the slider acceleration by about 1e-5 m/s² within the first revolution and by about 4e-2 m/s² by the end of the second. (docs/model.md §9)",
        criterion: "The realisations' pointwise spread of ẍ over the last revolution exceeds 1e-2 m/s² (dry_150rpm_c0.1).",
        note: "",
        eval: |v| Ok(v.less(1e-2, v.get(DRY_SPEEDS[1], Quantity::AccSpread)?)),
    },
];

/// Number of claims [`evaluate`] returns.
#[cfg(test)]
pub(crate) fn count() -> usize {
    DEFS.len()
}

/// Decides every claim from the runs: the verdict on the ensemble means, and the number of
/// realisations on which the criterion holds. Errors ([`Error::Internal`]): a case missing, a
/// statistic missing or non-finite.
pub(crate) fn evaluate(cases: &Cases) -> Result<Vec<Claim>, Error> {
    evaluate_with(cases, &Thresholds::paper())
}

/// [`evaluate`] with other thresholds.
pub(crate) fn evaluate_with(cases: &Cases, th: &Thresholds) -> Result<Vec<Claim>, Error> {
    let n = cases.values().map(|e| e.members.len()).max().unwrap_or(0);
    if n == 0 {
        return Err(Error::Internal(
            "study: no runs to judge the claims on".into(),
        ));
    }
    DEFS.iter()
        .map(|d| {
            let mean = View {
                cases,
                pick: Pick::Mean,
                log: RefCell::new(Vec::new()),
                th,
                margins: RefCell::new(Vec::new()),
            };
            let holds = (d.eval)(&mean)?;
            let margin = mean
                .margins
                .borrow()
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            let mut holding = 0;
            for k in 0..n {
                let one = View {
                    cases,
                    pick: Pick::Member(k),
                    log: RefCell::new(Vec::new()),
                    th,
                    margins: RefCell::new(Vec::new()),
                };
                holding += usize::from((d.eval)(&one)?);
            }
            Ok(Claim {
                id: d.id.into(),
                origin: d.origin,
                figure: d.figure.into(),
                statement: d.statement.into(),
                source: d.source.into(),
                criterion: d.criterion.into(),
                note: d.note.into(),
                margin,
                numbers: mean.log.into_inner(),
                verdict: Verdict::of(holds),
                realisations_holding: holding,
                realisations: n,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::metrics::Metrics;
    use crate::run::press::Kind;
    use crate::studies::paper::stats::{CaseStats, Deviations, Ensemble};

    /// Statistics of one realisation with the given values (everything else neutral).
    #[derive(Clone, Copy)]
    struct S {
        rms: f64,
        eps: Option<f64>,
        pen: Option<f64>,
        force: Option<f64>,
        x_dev: f64,
        x_bdc: f64,
        v_dev: f64,
        a_dev: f64,
        a_dc: f64,
        peak: f64,
        rel: (f64, f64, f64),
        sectors: usize,
        contact: Option<f64>,
        closure: Option<f64>,
    }

    fn stats(s: S) -> CaseStats {
        CaseStats {
            metrics: Metrics {
                slider_acc_max: Some(s.peak),
                slider_acc_min: Some(-s.peak),
                slider_acc_rms_dev_ideal: Some(s.rms),
                eps_max: s.eps,
                contact_onsets: s.eps.map(|_| 3),
                contact_force_max: s.force,
                penetration_max: s.pen,
                film_force_max: s.eps.map(|_| 0.0),
                film_thickness_min: None,
                slider_x_end: Some(0.365),
                constraint_violation_max: 1e-9,
                clearance_joints: Default::default(),
                energy: None,
            },
            dev: Deviations {
                stroke: 0.03,
                x_dev_max: s.x_dev,
                v_dev_max: s.v_dev,
                a_dev_max: s.a_dev,
                a_ideal_peak: s.peak,
                x_dev_bdc: s.x_bdc,
                a_dev_dead_centres: s.a_dc,
                x_dev_rel: s.rel.0,
                v_dev_rel: s.rel.1,
                a_dev_rel: s.rel.2,
                fluctuation_sectors: s.sectors,
                contact_fraction: s.contact,
                orbit_closure: s.closure,
            },
        }
    }

    const DRY: S = S {
        rms: 2.0,
        eps: Some(2.1),
        pen: Some(1.1e-4),
        force: Some(3.1e4),
        x_dev: 1.1e-4,
        x_bdc: 1.1e-4,
        v_dev: 0.02,
        a_dev: 5.0,
        a_dc: 5.0,
        peak: 3.86,
        rel: (0.01, 0.05, 0.9),
        sectors: 8,
        contact: Some(0.6),
        closure: Some(2.0),
    };
    const LUB: S = S {
        rms: 1e-3,
        eps: Some(0.5),
        pen: Some(0.0),
        force: Some(0.0),
        x_dev: 1e-5,
        x_bdc: 1e-5,
        v_dev: 1e-4,
        a_dev: 1e-3,
        a_dc: 1e-3,
        peak: 3.86,
        rel: (1e-3, 5e-4, 5e-4),
        sectors: 0,
        contact: Some(0.0),
        closure: Some(0.01),
    };

    /// A table on which every claim holds, two identical realisations per clearance case.
    fn paper_like() -> Cases {
        let mut c = Cases::new();
        let mut put = |case: PressCase, s: S, spread: f64| {
            let n = if case.kind() == Kind::Ideal { 1 } else { 2 };
            c.insert(
                RunKey::runs(case),
                Ensemble {
                    members: vec![stats(s); n],
                    acc_spread: spread,
                },
            );
        };
        for (i, name) in DRY_SPEEDS.iter().enumerate() {
            let k = i as f64;
            put(
                *name,
                S {
                    rms: 1.0 + k,
                    eps: Some(2.0 + 0.1 * k),
                    pen: Some(1e-4 * (1.0 + 0.1 * k)),
                    x_dev: 1e-4 * (1.0 + 0.1 * k),
                    x_bdc: 1e-4 * (1.0 + 0.1 * k),
                    v_dev: 0.01 * (1.0 + k),
                    a_dc: 4.0 + k,
                    peak: 2.5 + k,
                    contact: Some(0.5 + 0.1 * k),
                    ..DRY
                },
                5.0,
            );
        }
        for (j, name) in DRY_CLEARANCES.iter().enumerate().skip(1) {
            let (x, v, rms, contact, pen) = [
                (0.0, 0.0, 0.0, 0.0, 0.0),
                (2e-4, 0.03, 2.2, 0.55, 1.2e-4),
                (3e-4, 0.04, 3.0, 0.4, 1.3e-4),
                (5e-4, 0.05, 5.0, 0.3, 1.5e-4),
            ][j];
            put(
                *name,
                S {
                    rms,
                    x_dev: x,
                    v_dev: v,
                    contact: Some(contact),
                    pen: Some(pen),
                    eps: Some(1.5),
                    ..DRY
                },
                5.0,
            );
        }
        for (i, name) in LUB_SPEEDS.iter().enumerate() {
            put(
                *name,
                S {
                    peak: 2.5 + i as f64,
                    ..LUB
                },
                1e-4,
            );
        }
        for (j, name) in LUB_CLEARANCES.iter().enumerate().skip(1) {
            let (a_dev, eps) = [(0.0, 0.0), (0.01, 0.6), (0.02, 0.85), (0.3, 0.95)][j];
            put(
                *name,
                S {
                    a_dev,
                    eps: Some(eps),
                    ..LUB
                },
                1e-4,
            );
        }
        for name in IDEALS {
            put(
                name,
                S {
                    rms: 1e-9,
                    eps: None,
                    pen: None,
                    force: None,
                    contact: None,
                    closure: None,
                    ..LUB
                },
                0.0,
            );
        }
        c
    }

    fn verdict(cases: &Cases, id: &str) -> (Verdict, usize, usize) {
        let c = evaluate(cases).unwrap();
        let c = c.iter().find(|c| c.id == id).unwrap();
        (c.verdict, c.realisations_holding, c.realisations)
    }

    /// Applies `f` to every realisation of `case`.
    fn set(cases: &mut Cases, case: PressCase, f: impl Fn(&mut CaseStats)) {
        for m in cases
            .get_mut(&RunKey::runs(case))
            .unwrap()
            .members
            .iter_mut()
        {
            f(m);
        }
    }

    #[test]
    fn every_claim_holds_on_a_paper_like_table() {
        let claims = evaluate(&paper_like()).unwrap();
        assert_eq!(claims.len(), count());
        for c in &claims {
            assert_eq!(c.verdict, Verdict::Holds, "{}: {:?}", c.id, c.numbers);
            assert_eq!((c.realisations_holding, c.realisations), (2, 2), "{}", c.id);
            assert!(!c.numbers.is_empty(), "{} reads no number", c.id);
        }
        let ids: Vec<&str> = claims.iter().map(|c| c.id.as_str()).collect();
        let mut unique = ids.clone();
        unique.dedup();
        assert_eq!(ids, unique);
    }

    type Mutation = (&'static str, fn(&mut Cases));

    /// One change per claim that breaks exactly the property the claim asserts.
    const BREAKERS: &[Mutation] = &[
        ("P1", |c| {
            set(c, PressCase::dry(200, 100), |s| s.dev.x_dev_max = 3.1e-4)
        }), // > 1 % of 0.03 m
        ("P2", |c| {
            set(c, PressCase::dry(180, 100), |s| s.dev.x_dev_bdc = 1.35e-4)
        }), // > 200 rpm's 1.3e-4
        ("P3", |c| {
            set(c, PressCase::dry(120, 100), |s| s.dev.v_dev_rel = 0.95)
        }),
        ("P4", |c| {
            set(c, PressCase::dry(150, 100), |s| {
                s.dev.fluctuation_sectors = 7
            })
        }),
        ("P5", |c| {
            set(c, PressCase::dry(200, 100), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(3.0)
            })
        }),
        ("P6", |c| {
            set(c, PressCase::dry(120, 100), |s| {
                s.dev.a_dev_dead_centres = 5.0
            })
        }),
        ("P7", |c| {
            set(c, PressCase::dry(200, 100), |s| {
                s.dev.contact_fraction = Some(0.7)
            })
        }),
        ("P8", |c| {
            set(c, PressCase::dry(180, 100), |s| {
                s.metrics.penetration_max = Some(1.1e-4)
            })
        }),
        ("P9", |c| {
            set(c, PressCase::lubricated(180, 100), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(3.5)
            })
        }),
        ("P10", |c| {
            set(c, PressCase::lubricated(120, 100), |s| {
                s.dev.x_dev_bdc = 1e-4
            })
        }),
        ("P11", |c| {
            set(c, PressCase::lubricated(200, 100), |s| {
                s.dev.v_dev_max = 0.05
            })
        }),
        ("P12", |c| {
            set(c, PressCase::lubricated(200, 100), |s| {
                s.dev.a_dev_max = 0.06
            })
        }), // 1 % of 5.5 = 0.055
        ("P13", |c| {
            set(c, PressCase::lubricated(120, 100), |s| {
                s.metrics.eps_max = Some(1.0)
            })
        }),
        ("P14", |c| {
            set(c, PressCase::dry(150, 300), |s| s.dev.x_dev_max = 1.5e-4)
        }),
        ("P15", |c| {
            set(c, PressCase::dry(150, 500), |s| s.dev.v_dev_max = 0.035)
        }),
        ("P16", |c| {
            // 3.7 / 3.0 < 1.25 although the curve still steepens: (3.7−3)/0.2 > (3−2)/0.2.
            set(c, PressCase::dry(150, 500), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(3.7)
            })
        }),
        ("P17", |c| {
            set(c, PressCase::dry(150, 300), |s| {
                s.dev.contact_fraction = Some(0.56)
            })
        }),
        ("P18", |c| {
            set(c, PressCase::dry(150, 500), |s| {
                s.metrics.penetration_max = Some(1.3e-4)
            })
        }),
        ("P19", |c| {
            set(c, PressCase::lubricated(150, 300), |s| {
                s.dev.x_dev_max = 4e-4
            })
        }),
        ("P20", |c| {
            set(c, PressCase::lubricated(150, 500), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(6.0)
            })
        }),
        ("P21", |c| {
            set(c, PressCase::lubricated(150, 500), |s| {
                s.dev.a_dev_max = 0.19
            })
        }), // < 5 % of 3.86
        ("P22", |c| {
            set(c, PressCase::lubricated(150, 200), |s| {
                s.metrics.eps_max = Some(0.9)
            })
        }),
        ("P23", |c| {
            set(c, PressCase::lubricated(150, 500), |s| {
                s.metrics.eps_max = Some(1.01)
            })
        }),
        ("P24", |c| {
            c.get_mut(&RunKey::runs(PressCase::lubricated(150, 300)))
                .unwrap()
                .acc_spread = 4e-3
        }),
        ("P25", |c| {
            set(c, PressCase::lubricated(150, 200), |s| {
                s.dev.orbit_closure = Some(0.05)
            })
        }),
        ("M1", |c| {
            set(c, PressCase::ideal(180), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(1e-5)
            })
        }),
        ("M2", |c| {
            set(c, PressCase::dry(150, 100), |s| {
                s.metrics.contact_force_max = Some(2.9e4)
            })
        }),
        ("M3", |c| {
            set(c, PressCase::lubricated(150, 100), |s| {
                s.metrics.slider_acc_rms_dev_ideal = Some(2e-3)
            })
        }),
        ("M4", |c| {
            c.get_mut(&RunKey::runs(PressCase::dry(150, 100)))
                .unwrap()
                .acc_spread = 1e-2
        }),
    ];

    #[test]
    fn every_claim_fails_when_its_property_is_broken() {
        assert_eq!(BREAKERS.len(), count());
        for (id, breaker) in BREAKERS {
            let mut cases = paper_like();
            breaker(&mut cases);
            let claims = evaluate(&cases).unwrap();
            for c in &claims {
                let want = if c.id == *id {
                    Verdict::DoesNotHold
                } else {
                    Verdict::Holds
                };
                assert_eq!(c.verdict, want, "breaking {id} changed {}", c.id);
            }
            let c = claims.iter().find(|c| c.id == *id).unwrap();
            assert_eq!(c.realisations_holding, 0, "{id}");
        }
    }

    #[test]
    fn verdict_is_on_the_means_and_realisations_are_counted() {
        // P5 at 200 rpm: realisation 0 has RMS 5 (> 180 rpm's 3), realisation 1 has 2.5 (< 3).
        // Mean 3.75 > 3: HOLDS on the means, 1 of 2 realisations.
        let mut cases = paper_like();
        let e = cases
            .get_mut(&RunKey::runs(PressCase::dry(200, 100)))
            .unwrap();
        e.members[0].metrics.slider_acc_rms_dev_ideal = Some(5.0);
        e.members[1].metrics.slider_acc_rms_dev_ideal = Some(2.5);
        assert_eq!(verdict(&cases, "P5"), (Verdict::Holds, 1, 2));
        let p5 = evaluate(&cases)
            .unwrap()
            .into_iter()
            .find(|c| c.id == "P5")
            .unwrap();
        let n = p5
            .numbers
            .iter()
            .find(|n| n.label == "dry_200rpm_c0.1 slider_acc_rms_dev_ideal")
            .unwrap();
        assert_eq!((n.value, n.min, n.max), (3.75, Some(2.5), Some(5.0)));
        // Mean 2.9 < 3: DOES NOT HOLD although realisation 0 still satisfies it.
        let e = cases
            .get_mut(&RunKey::runs(PressCase::dry(200, 100)))
            .unwrap();
        e.members[1].metrics.slider_acc_rms_dev_ideal = Some(0.8);
        assert_eq!(verdict(&cases, "P5"), (Verdict::DoesNotHold, 1, 2));
    }

    #[test]
    fn missing_data_is_an_error_not_a_verdict() {
        let mut cases = paper_like();
        cases.remove(&RunKey::runs(PressCase::lubricated(150, 500)));
        let e = evaluate(&cases).unwrap_err();
        assert!(
            e.to_string()
                .contains("no runs of case lubricated_150rpm_c0.5"),
            "{e}"
        );
        let mut cases = paper_like();
        set(&mut cases, PressCase::dry(120, 100), |s| {
            s.metrics.penetration_max = None
        });
        assert!(evaluate(&cases)
            .unwrap_err()
            .to_string()
            .contains("dry_120rpm_c0.1 has no penetration_max"));
        let mut cases = paper_like();
        set(&mut cases, PressCase::dry(120, 100), |s| {
            s.dev.x_dev_max = f64::NAN
        });
        assert!(evaluate(&cases).is_err());
        assert!(evaluate(&Cases::new()).is_err());
    }
}
