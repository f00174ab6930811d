//! Butcher tableaus of the explicit embedded pairs, as `const` data.
//!
//! ```text
//!  c | A          stage i:  k_i = f(t + c_i h, y_n + h Σ_{j<i} a_ij k_j)
//! ---+-----       y_{n+1} = y_n + h Σ b_i k_i           (order p)
//!    | bᵀ         err     = h Σ e_i k_i,  e = b − b̂     (b̂ of order p̂)
//!    | eᵀ         dense:  y(t_n + θh) = y_n + h Σ_i b_i(θ) k_i
//! ```
//!
//! Rows of `a` hold only the strictly lower part: row i has i entries. Stages after the main
//! ones (index ≥ `b.len()`) exist only for the dense output. Every number is as printed in the
//! source named above its tableau; the test `tests/erk_tableaus.rs` checks row sums, the order
//! conditions of b, b̂ and the continuous extension for all rooted trees, and FSAL consistency.

// Published coefficients carry more digits than an f64 holds; they are kept as printed.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

/// How the dense output of a step is built.
///
/// ```text
/// y(t_n + θh) = y_n + h Σ_i b_i(θ) k_i,   b_i(0) = 0,  b_i(1) = b_i
/// ```
/// (HNW I §II.6, continuous Runge–Kutta methods).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dense {
    /// Cubic Hermite interpolation through (y_n, f_n) and (y_{n+1}, f_{n+1}), order 3; f_{n+1}
    /// is the FSAL stage, so it costs nothing.
    ///
    /// ```text
    /// y(θ) = (1 − 3θ² + 2θ³) y_n + (θ − 2θ² + θ³) h f_n + (3θ² − 2θ³) y_{n+1} + (θ³ − θ²) h f_{n+1}
    /// ```
    Hermite3,
    /// Hairer's form of the continuous extensions of DOPRI5 and DOP853 (HNW I, §II.6; the
    /// codes dopri5.f and dop853.f): with Δ = y_{n+1} − y_n, s₂ = h f_n − Δ,
    /// s₃ = Δ − h f_{n+1} − s₂ and s_{m} = h Σ_j d_{m,j} k_j (m = 4, …),
    ///
    /// ```text
    /// y(θ) = y_n + θ(Δ + (1−θ)(s₂ + θ(s₃ + (1−θ)(s₄ + θ(s₅ + (1−θ)(s₆ + θ s₇))))))
    /// ```
    Hairer {
        /// Rows d_4, d_5, …; each has one entry per stage (extra dense stages included).
        d: &'static [&'static [f64]],
    },
    /// Weights given as polynomials b_i(θ) = Σ_m r_{i,m} θ^{m+1}, one row per stage.
    Polynomial {
        /// r_{i,m}: row i holds the coefficients of θ, θ², … of b_i(θ).
        r: &'static [&'static [f64]],
    },
}

/// How the local error estimate is formed from the stages.
///
/// ```text
/// ε = ‖h Σ_i e_i k_i‖,  e = b − b̂        (HNW I §II.4, embedded formulas)
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorEstimate {
    /// One embedded formula: ‖h Σ e_i k_i‖ with e = b − b̂.
    Embedded {
        /// e = b − b̂ (one entry per main stage).
        e: &'static [f64],
    },
    /// DOP853's combination of a 5th- and a 3rd-order estimate (HNW I, §II.10, p. 254;
    /// dop853.f): with E₅ = ‖h Σ e5_i k_i‖ and E₃ = ‖h Σ (b − b̂3)_i k_i‖ in the weighted RMS
    /// norm, err = E₅² / √(E₅² + 0.01 E₃²), which behaves like O(h⁸).
    Dop853 {
        /// e5 = b − b̂5 ("er" in dop853.f).
        e5: &'static [f64],
        /// b̂3, the weights of the 3rd-order formula ("bhh" in dop853.f).
        b3: &'static [f64],
    },
}

/// An explicit embedded Runge–Kutta pair with its continuous extension.
///
/// ```text
/// k_i = f(t_n + c_i h, y_n + h Σ_{j<i} a_ij k_j),  y_{n+1} = y_n + h Σ b_i k_i
/// ```
/// (Butcher tableau notation, HNW I §II.1 (1.8)); the constants of this module name their
/// sources.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tableau {
    /// Short name (the method's CLI name).
    pub name: &'static str,
    /// Order p of the propagated solution (b).
    pub order: usize,
    /// Order p̂ of the embedded solution b̂ (for DOP853: the 5th-order formula).
    pub embedded_order: usize,
    /// Order q of the dense output.
    pub dense_order: usize,
    /// The error estimate behaves like h^(q̂+1); this q̂ sets the controller exponent
    /// 1/(q̂+1) and the starting step. Equals `embedded_order` except for DOP853 (7).
    pub estimate_order: usize,
    /// Nodes c_i, one per stage (extra dense stages included).
    pub c: &'static [f64],
    /// Strictly lower triangular A: row i has i entries (extra dense stages included).
    pub a: &'static [&'static [f64]],
    /// Weights b of the propagated solution, one per main stage.
    pub b: &'static [f64],
    /// The error estimate.
    pub error: ErrorEstimate,
    /// First same as last: the last main stage is f(t_{n+1}, y_{n+1}) (its row of A equals b).
    pub fsal: bool,
    /// The continuous extension.
    pub dense: Dense,
}

impl Tableau {
    /// Number of main stages s (the length of b).
    pub fn stages(&self) -> usize {
        self.b.len()
    }

    /// Index of the stage that holds f(t_{n+1}, y_{n+1}) after an accepted step: the last main
    /// stage of an FSAL pair, else one extra stage s whose row of A is b.
    pub fn f_new_stage(&self) -> usize {
        if self.fsal {
            self.b.len() - 1
        } else {
            self.b.len()
        }
    }

    /// Number of stages the stepper stores: the main ones, the f(t_{n+1}, y_{n+1}) stage of a
    /// non-FSAL pair, and the extra dense-output stages.
    pub fn total_stages(&self) -> usize {
        self.c.len()
    }

    /// Checks the shapes of the data (row i of A has i entries, one node per stage, weights
    /// and error weights over the main stages, dense data over all stages, FSAL rows equal
    /// to b) so that a custom tableau cannot make the stepper index out of bounds.
    pub fn validate(&self) -> Result<(), String> {
        let ns = self.c.len();
        let s = self.b.len();
        if s == 0 || self.a.len() != ns {
            return Err(format!(
                "{}: A has {} rows, c {} entries",
                self.name,
                self.a.len(),
                ns
            ));
        }
        if let Some(i) = (0..ns).find(|&i| self.a[i].len() != i) {
            return Err(format!("{}: row {i} of A must have {i} entries", self.name));
        }
        if self.f_new_stage() >= ns {
            return Err(format!("{}: no stage holds f(t+h, y_(n+1))", self.name));
        }
        if self.a[self.f_new_stage()] != &self.b[..self.f_new_stage()] {
            return Err(format!(
                "{}: the f(t+h, y_(n+1)) row of A must equal b",
                self.name
            ));
        }
        let e_ok = match self.error {
            ErrorEstimate::Embedded { e } => e.len() == s,
            ErrorEstimate::Dop853 { e5, b3 } => e5.len() == s && b3.len() == s,
        };
        if !e_ok {
            return Err(format!("{}: error weights need {s} entries", self.name));
        }
        let dense_ok = match self.dense {
            Dense::Hermite3 => true,
            Dense::Hairer { d } => d.len() <= 4 && d.iter().all(|r| r.len() == ns),
            Dense::Polynomial { r } => r.len() == ns,
        };
        if !dense_ok {
            return Err(format!(
                "{}: dense-output data has the wrong shape",
                self.name
            ));
        }
        Ok(())
    }

    /// Weights b̂ of the embedded solution (b − e; for DOP853 the 5th-order one).
    pub fn b_hat(&self) -> Vec<f64> {
        let e = match self.error {
            ErrorEstimate::Embedded { e } => e,
            ErrorEstimate::Dop853 { e5, .. } => e5,
        };
        self.b.iter().zip(e).map(|(b, e)| b - e).collect()
    }

    /// The dense-output weights as polynomials in θ: entry `[i][m]` is the coefficient of
    /// θ^(m+1) in b_i(θ), for every stored stage i, so that
    /// y(t_n + θh) = y_n + h Σ_i b_i(θ) k_i.
    pub fn dense_weights(&self) -> Vec<Vec<f64>> {
        let ns = self.total_stages();
        let s = self.stages();
        let fnew = self.f_new_stage();
        let bi = |i: usize| if i < s { self.b[i] } else { 0.0 };
        let delta = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
        match self.dense {
            Dense::Hermite3 => (0..ns)
                .map(|i| {
                    // (3θ² − 2θ³) b_i + (θ − 2θ² + θ³) δ_i0 + (θ³ − θ²) δ_i,fnew
                    let (b, d0, d1) = (bi(i), delta(i, 0), delta(i, fnew));
                    vec![d0, 3.0 * b - 2.0 * d0 - d1, -2.0 * b + d0 + d1]
                })
                .collect(),
            Dense::Hairer { d } => {
                // Basis φ₁ = θ, φ₂ = θ(1−θ), φ₃ = θ²(1−θ), φ₄ = θ²(1−θ)², φ₅ = θ³(1−θ)²,
                // φ₆ = θ³(1−θ)³, φ₇ = θ⁴(1−θ)³, as monomial coefficients of θ¹…θ⁷.
                const PHI: [[f64; 7]; 7] = [
                    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                    [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, -2.0, 1.0, 0.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, -2.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, -3.0, 3.0, -1.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0, -3.0, 3.0, -1.0],
                ];
                let deg = 3 + d.len();
                (0..ns)
                    .map(|i| {
                        // Coefficients of stage i on the basis: Δ → b_i, s₂ → δ_i0 − b_i,
                        // s₃ → b_i − δ_i,fnew − (δ_i0 − b_i), s_m → d_{m,i}.
                        let b = bi(i);
                        let s2 = delta(i, 0) - b;
                        let mut coef = vec![b, s2, b - delta(i, fnew) - s2];
                        coef.extend(d.iter().map(|row| row[i]));
                        let mut r = vec![0.0; deg];
                        for (q, cq) in coef.iter().enumerate() {
                            for m in 0..deg {
                                r[m] += cq * PHI[q][m];
                            }
                        }
                        r
                    })
                    .collect()
            }
            Dense::Polynomial { r } => (0..ns)
                .map(|i| if i < r.len() { r[i].to_vec() } else { vec![] })
                .collect(),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Bogacki–Shampine 3(2)
//
// P. Bogacki, L. F. Shampine, "A 3(2) pair of Runge–Kutta formulas", Appl. Math. Lett. 2(4)
// (1989) 321–325, the tableau of the pair (4 stages, FSAL). No continuous extension is
// published with it: the dense output is the cubic Hermite interpolant (order 3).
// ---------------------------------------------------------------------------------------------

/// Bogacki–Shampine 3(2): order 3, embedded order 2, FSAL, Hermite dense output.
///
/// ```text
///   0  |
///  1/2 | 1/2
///  3/4 | 0    3/4
///   1  | 2/9  1/3  4/9
/// -----+---------------------
///   b  | 2/9  1/3  4/9  0
///   b̂  | 7/24 1/4  1/3  1/8
/// ```
/// Bogacki & Shampine (1989), Appl. Math. Lett. 2(4) 321–325.
pub const BS32: Tableau = Tableau {
    name: "bs32",
    order: 3,
    embedded_order: 2,
    dense_order: 3,
    estimate_order: 2,
    c: &[0.0, 1.0 / 2.0, 3.0 / 4.0, 1.0],
    a: &[
        &[],
        &[1.0 / 2.0],
        &[0.0, 3.0 / 4.0],
        &[2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0],
    ],
    b: &[2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0],
    // e = b − b̂ = (2/9 − 7/24, 1/3 − 1/4, 4/9 − 1/3, 0 − 1/8)
    error: ErrorEstimate::Embedded {
        e: &[-5.0 / 72.0, 1.0 / 12.0, 1.0 / 9.0, -1.0 / 8.0],
    },
    fsal: true,
    dense: Dense::Hermite3,
};

// ---------------------------------------------------------------------------------------------
// Dormand–Prince 5(4)
//
// J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta formulae", J. Comput. Appl.
// Math. 6 (1980) 19–26; HNW I (Hairer, Nørsett, Wanner, Solving ODEs I, 2nd ed., 1993),
// Table 5.2, p. 178. Continuous extension of order 4: HNW I, §II.6, p. 191–192 (due to
// Shampine 1986 / Dormand & Prince 1986), in the d-coefficient form of Hairer's dopri5.f.
// ---------------------------------------------------------------------------------------------

const DOPRI54_B: [f64; 7] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
    0.0,
];

/// Dormand–Prince 5(4) ("DOPRI5"): order 5, embedded order 4, FSAL, dense output of order 4.
///
/// ```text
///   0   |
///  1/5  | 1/5
///  3/10 | 3/40        9/40
///  4/5  | 44/45      −56/15       32/9
///  8/9  | 19372/6561 −25360/2187  64448/6561 −212/729
///   1   | 9017/3168  −355/33      46732/5247  49/176   −5103/18656
///   1   | 35/384      0           500/1113    125/192  −2187/6784   11/84
/// ------+--------------------------------------------------------------------------
///   b   | 35/384      0           500/1113    125/192  −2187/6784   11/84    0
///   b̂   | 5179/57600  0           7571/16695  393/640  −92097/339200 187/2100 1/40
/// ```
/// HNW I, Table 5.2, p. 178; dense output HNW I §II.6 (Hairer's dopri5.f coefficients d_i).
pub const DOPRI54: Tableau = Tableau {
    name: "dopri54",
    order: 5,
    embedded_order: 4,
    dense_order: 4,
    estimate_order: 4,
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ],
        &[
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ],
        &[
            DOPRI54_B[0],
            DOPRI54_B[1],
            DOPRI54_B[2],
            DOPRI54_B[3],
            DOPRI54_B[4],
            DOPRI54_B[5],
        ],
    ],
    b: &DOPRI54_B,
    // e = b − b̂ (HNW I, Table 5.2; the "E" coefficients of dopri5.f).
    error: ErrorEstimate::Embedded {
        e: &[
            71.0 / 57600.0,
            0.0,
            -71.0 / 16695.0,
            71.0 / 1920.0,
            -17253.0 / 339200.0,
            22.0 / 525.0,
            -1.0 / 40.0,
        ],
    },
    fsal: true,
    dense: Dense::Hairer {
        d: &[&[
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]],
    },
};

// ---------------------------------------------------------------------------------------------
// Tsitouras 5(4)
//
// Ch. Tsitouras, "Runge–Kutta pairs of order 5(4) satisfying only the first column simplifying
// assumption", Comput. Math. Appl. 62 (2011) 770–775, doi:10.1016/j.camwa.2011.06.002: the
// coefficients c_i, a_ij (j ≥ 2; a_i1 = c_i − Σ_{j≥2} a_ij), b_i and b_i − b̂_i, and the
// continuous extension b_i(θ) of order 4 printed in factored form in the paper. Digits
// cross-checked against the 80-digit values of OrdinaryDiffEq.jl's Tsit5 tableau.
// ---------------------------------------------------------------------------------------------

const TSIT54_B: [f64; 7] = [
    0.09646076681806523,
    0.01,
    0.4798896504144996,
    1.379008574103742,
    -3.290069515436081,
    2.324710524099774,
    0.0,
];

/// Expands lead·θ²·(θ² + q[1] θ + q[2]) (q[0] = 1) into the coefficients of θ¹…θ⁴.
const fn poly4(lead: f64, q: [f64; 3]) -> [f64; 4] {
    [0.0, lead * q[2], lead * q[1], lead * q[0]]
}

/// Quadratic (θ − r1)(θ − r2) as [1, −(r1 + r2), r1 r2].
const fn roots2(r1: f64, r2: f64) -> [f64; 3] {
    [1.0, -(r1 + r2), r1 * r2]
}

const TSIT54_R1: [f64; 4] = {
    // b1(θ) = −1.0530884977290216 θ (θ − 1.3299890189751412)
    //          · (θ² − 1.4364028541716351 θ + 0.7139816917074209)
    let k = -1.0530884977290216;
    let r = 1.3299890189751412;
    let (q1, q0) = (-1.4364028541716351, 0.7139816917074209);
    // θ (θ − r)(θ² + q1 θ + q0) = θ⁴ + (q1 − r) θ³ + (q0 − r q1) θ² − r q0 θ
    [k * (-r * q0), k * (q0 - r * q1), k * (q1 - r), k]
};

const TSIT54_R: [[f64; 4]; 7] = [
    TSIT54_R1,
    // b2(θ) = 0.1017 θ² (θ² − 2.1966568338249754 θ + 1.2949852507374631)
    poly4(0.1017, [1.0, -2.1966568338249754, 1.2949852507374631]),
    // b3(θ) = 2.490627285651252793 θ² (θ² − 2.38535645472061657 θ + 1.57803468208092486)
    poly4(
        2.490627285651252793,
        [1.0, -2.38535645472061657, 1.57803468208092486],
    ),
    // b4(θ) = −16.54810288924490272 (θ − 1.21712927295533244)(θ − 0.61620406037800089) θ²
    poly4(
        -16.54810288924490272,
        roots2(1.21712927295533244, 0.61620406037800089),
    ),
    // b5(θ) = 47.37952196281928122 (θ − 1.203071208372362603)(θ − 0.658047292653547382) θ²
    poly4(
        47.37952196281928122,
        roots2(1.203071208372362603, 0.658047292653547382),
    ),
    // b6(θ) = −34.87065786149660974 (θ − 1.2)(θ − 0.666666666666666667) θ²
    poly4(-34.87065786149660974, roots2(1.2, 0.666666666666666667)),
    // b7(θ) = 2.5 (θ − 1)(θ − 0.6) θ²
    poly4(2.5, roots2(1.0, 0.6)),
];

/// Tsitouras 5(4) ("Tsit5"): order 5, embedded order 4, FSAL, dense output of order 4.
///
/// ```text
/// c = (0, 0.161, 0.327, 0.9, 0.9800255409045097, 1, 1)
/// a_i1 = c_i − Σ_{j≥2} a_ij (first column simplifying assumption), b = row 7 of A,
/// b7 = 0, b̂7 = 1/66; interpolant b_i(θ) of order 4 (quartic in θ).
/// ```
/// Tsitouras (2011), Comput. Math. Appl. 62, 770–775.
pub const TSIT54: Tableau = Tableau {
    name: "tsit54",
    order: 5,
    embedded_order: 4,
    dense_order: 4,
    estimate_order: 4,
    c: &[0.0, 0.161, 0.327, 0.9, 0.9800255409045097, 1.0, 1.0],
    a: &[
        &[],
        &[0.161],
        &[-0.008480655492356989, 0.335480655492357],
        &[2.8971530571054935, -6.359448489975075, 4.3622954328695815],
        &[
            5.325864828439257,
            -11.748883564062828,
            7.4955393428898365,
            -0.09249506636175525,
        ],
        &[
            5.86145544294642,
            -12.92096931784711,
            8.159367898576159,
            -0.071584973281401,
            -0.028269050394068383,
        ],
        &[
            TSIT54_B[0],
            TSIT54_B[1],
            TSIT54_B[2],
            TSIT54_B[3],
            TSIT54_B[4],
            TSIT54_B[5],
        ],
    ],
    b: &TSIT54_B,
    // e = b − b̂.
    error: ErrorEstimate::Embedded {
        e: &[
            0.001780011052225771443,
            0.0008164344596567469032,
            -0.007880878010261996010,
            0.144711007173262907537,
            -0.5823571654525552250199,
            0.4580821059291869466616,
            -1.0 / 66.0,
        ],
    },
    fsal: true,
    dense: Dense::Polynomial {
        r: &[
            &TSIT54_R[0],
            &TSIT54_R[1],
            &TSIT54_R[2],
            &TSIT54_R[3],
            &TSIT54_R[4],
            &TSIT54_R[5],
            &TSIT54_R[6],
        ],
    },
};

// ---------------------------------------------------------------------------------------------
// Dormand–Prince 8(5,3) — DOP853
//
// P. J. Prince, J. R. Dormand, "High order embedded Runge–Kutta formulae", J. Comput. Appl.
// Math. 7 (1981) 67–75, as reoptimised in HNW I §II.5 (p. 181, "DOP853") and §II.10 (error
// estimator, p. 254); the coefficients are those of Hairer & Wanner's code dop853.f (version of
// 25 April 1996, corrections 4 March 2002), parameters c_i, a_ij, b_i, bhh_i, er_i, and the
// three extra stages 14–16 and d_{4..7,i} of its dense output of order 7 (HNW I §II.6).
// Stage 13 is f(t_{n+1}, y_{n+1}) (its row of A is b), the next step's first stage.
// ---------------------------------------------------------------------------------------------

const DOP853_B: [f64; 12] = [
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566e0,
    1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// DOP853: order 8, error estimators of orders 5 and 3, dense output of order 7 (3 extra
/// stages, evaluated only when the dense output of a step is used).
///
/// ```text
/// 12 stages + f(t_{n+1}, y_{n+1}) (reused as the next k₁) + 3 dense stages
/// c = (0, c₂…c₁₁, 1 | 1 | 1/10, 1/5, 7/9)
/// err = E₅² / √(E₅² + 0.01 E₃²)
/// ```
/// HNW I §II.5, §II.6, §II.10; coefficients of dop853.f.
pub const DOP853: Tableau = Tableau {
    name: "dop853",
    order: 8,
    embedded_order: 5,
    dense_order: 7,
    estimate_order: 7,
    c: &[
        0.0,
        0.526001519587677318785587544488e-01,
        0.789002279381515978178381316732e-01,
        0.118350341907227396726757197510e+00,
        0.281649658092772603273242802490e+00,
        0.333333333333333333333333333333e+00,
        0.25e+00,
        0.307692307692307692307692307692e+00,
        0.651282051282051282051282051282e+00,
        0.6e+00,
        0.857142857142857142857142857142e+00,
        1.0,
        1.0,
        0.1e+00,
        0.2e+00,
        0.777777777777777777777777777778e+00,
    ],
    a: &[
        &[],
        &[5.26001519587677318785587544488e-2],
        &[
            1.97250569845378994544595329183e-2,
            5.91751709536136983633785987549e-2,
        ],
        &[
            2.95875854768068491816892993775e-2,
            0.0,
            8.87627564304205475450678981324e-2,
        ],
        &[
            2.41365134159266685502369798665e-1,
            0.0,
            -8.84549479328286085344864962717e-1,
            9.24834003261792003115737966543e-1,
        ],
        &[
            3.7037037037037037037037037037e-2,
            0.0,
            0.0,
            1.70828608729473871279604482173e-1,
            1.25467687566822425016691814123e-1,
        ],
        &[
            3.7109375e-2,
            0.0,
            0.0,
            1.70252211019544039314978060272e-1,
            6.02165389804559606850219397283e-2,
            -1.7578125e-2,
        ],
        &[
            3.70920001185047927108779319836e-2,
            0.0,
            0.0,
            1.70383925712239993810214054705e-1,
            1.07262030446373284651809199168e-1,
            -1.53194377486244017527936158236e-2,
            8.27378916381402288758473766002e-3,
        ],
        &[
            6.24110958716075717114429577812e-1,
            0.0,
            0.0,
            -3.36089262944694129406857109825e0,
            -8.68219346841726006818189891453e-1,
            2.75920996994467083049415600797e1,
            2.01540675504778934086186788979e1,
            -4.34898841810699588477366255144e1,
        ],
        &[
            4.77662536438264365890433908527e-1,
            0.0,
            0.0,
            -2.48811461997166764192642586468e0,
            -5.90290826836842996371446475743e-1,
            2.12300514481811942347288949897e1,
            1.52792336328824235832596922938e1,
            -3.32882109689848629194453265587e1,
            -2.03312017085086261358222928593e-2,
        ],
        &[
            -9.3714243008598732571704021658e-1,
            0.0,
            0.0,
            5.18637242884406370830023853209e0,
            1.09143734899672957818500254654e0,
            -8.14978701074692612513997267357e0,
            -1.85200656599969598641566180701e1,
            2.27394870993505042818970056734e1,
            2.49360555267965238987089396762e0,
            -3.0467644718982195003823669022e0,
        ],
        &[
            2.27331014751653820792359768449e0,
            0.0,
            0.0,
            -1.05344954667372501984066689879e1,
            -2.00087205822486249909675718444e0,
            -1.79589318631187989172765950534e1,
            2.79488845294199600508499808837e1,
            -2.85899827713502369474065508674e0,
            -8.87285693353062954433549289258e0,
            1.23605671757943030647266201528e1,
            6.43392746015763530355970484046e-1,
        ],
        // Stage 13: f(t_{n+1}, y_{n+1}).
        &DOP853_B,
        // Stages 14–16: dense output only.
        &[
            5.61675022830479523392909219681e-2,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            2.53500210216624811088794765333e-1,
            -2.46239037470802489917441475441e-1,
            -1.24191423263816360469010140626e-1,
            1.5329179827876569731206322685e-1,
            8.20105229563468988491666602057e-3,
            7.56789766054569976138603589584e-3,
            -8.298e-3,
        ],
        &[
            3.18346481635021405060768473261e-2,
            0.0,
            0.0,
            0.0,
            0.0,
            2.83009096723667755288322961402e-2,
            5.35419883074385676223797384372e-2,
            -5.49237485713909884646569340306e-2,
            0.0,
            0.0,
            -1.08347328697249322858509316994e-4,
            3.82571090835658412954920192323e-4,
            -3.40465008687404560802977114492e-4,
            1.41312443674632500278074618366e-1,
        ],
        &[
            -4.28896301583791923408573538692e-1,
            0.0,
            0.0,
            0.0,
            0.0,
            -4.69762141536116384314449447206e0,
            7.68342119606259904184240953878e0,
            4.06898981839711007970213554331e0,
            3.56727187455281109270669543021e-1,
            0.0,
            0.0,
            0.0,
            -1.39902416515901462129418009734e-3,
            2.9475147891527723389556272149e0,
            -9.15095847217987001081870187138e0,
        ],
    ],
    b: &DOP853_B,
    error: ErrorEstimate::Dop853 {
        e5: &[
            0.1312004499419488073250102996e-01,
            0.0,
            0.0,
            0.0,
            0.0,
            -0.1225156446376204440720569753e+01,
            -0.4957589496572501915214079952e+00,
            0.1664377182454986536961530415e+01,
            -0.3503288487499736816886487290e+00,
            0.3341791187130174790297318841e+00,
            0.8192320648511571246570742613e-01,
            -0.2235530786388629525884427845e-01,
        ],
        b3: &[
            0.244094488188976377952755905512e+00,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.733846688281611857341361741547e+00,
            0.0,
            0.0,
            0.220588235294117647058823529412e-01,
        ],
    },
    fsal: false,
    dense: Dense::Hairer {
        d: &[
            &[
                -0.84289382761090128651353491142e+01,
                0.0,
                0.0,
                0.0,
                0.0,
                0.56671495351937776962531783590e+00,
                -0.30689499459498916912797304727e+01,
                0.23846676565120698287728149680e+01,
                0.21170345824450282767155149946e+01,
                -0.87139158377797299206789907490e+00,
                0.22404374302607882758541771650e+01,
                0.63157877876946881815570249290e+00,
                -0.88990336451333310820698117400e-01,
                0.18148505520854727256656404962e+02,
                -0.91946323924783554000451984436e+01,
                -0.44360363875948939664310572000e+01,
            ],
            &[
                0.10427508642579134603413151009e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                0.24228349177525818288430175319e+03,
                0.16520045171727028198505394887e+03,
                -0.37454675472269020279518312152e+03,
                -0.22113666853125306036270938578e+02,
                0.77334326684722638389603898808e+01,
                -0.30674084731089398182061213626e+02,
                -0.93321305264302278729567221706e+01,
                0.15697238121770843886131091075e+02,
                -0.31139403219565177677282850411e+02,
                -0.93529243588444783865713862664e+01,
                0.35816841486394083752465898540e+02,
            ],
            &[
                0.19985053242002433820987653617e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.38703730874935176555105901742e+03,
                -0.18917813819516756882830838328e+03,
                0.52780815920542364900561016686e+03,
                -0.11573902539959630126141871134e+02,
                0.68812326946963000169666922661e+01,
                -0.10006050966910838403183860980e+01,
                0.77771377980534432092869265740e+00,
                -0.27782057523535084065932004339e+01,
                -0.60196695231264120758267380846e+02,
                0.84320405506677161018159903784e+02,
                0.11992291136182789328035130030e+02,
            ],
            &[
                -0.25693933462703749003312586129e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.15418974869023643374053993627e+03,
                -0.23152937917604549567536039109e+03,
                0.35763911791061412378285349910e+03,
                0.93405324183624310003907691704e+02,
                -0.37458323136451633156875139351e+02,
                0.10409964950896230045147246184e+03,
                0.29840293426660503123344363579e+02,
                -0.43533456590011143754432175058e+02,
                0.96324553959188282948394950600e+02,
                -0.39177261675615439165231486172e+02,
                -0.14972683625798562581422125276e+03,
            ],
        ],
    },
};
