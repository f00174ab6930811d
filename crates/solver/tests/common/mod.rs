//! Test problems with closed forms or published reference values, shared by the solver tests
//! (the explicit pairs, RK4, and the bouncing ball of the stiff methods' event tests).
#![allow(dead_code)]
// Published values are kept with all their printed digits.
#![allow(clippy::excessive_precision)]

use lash_solver::*;

/// Kepler's two-body problem with eccentricity e, started at pericentre (HNW I, §II.10,
/// problem (10.1)): q'' = −q/|q|³, period 2π.
///
/// ```text
/// E − e sin E = t,  q = (cos E − e, √(1−e²) sin E),  p = (−sin E, √(1−e²) cos E)/(1 − e cos E)
/// ```
pub struct Kepler {
    pub e: f64,
}

impl Kepler {
    /// Exact state at time t (Kepler's equation by Newton's method).
    pub fn exact(&self, t: f64) -> [f64; 4] {
        let e = self.e;
        let mut ea = t;
        for _ in 0..50 {
            let d = (ea - e * ea.sin() - t) / (1.0 - e * ea.cos());
            ea -= d;
            if d.abs() < 1e-16 {
                break;
            }
        }
        let s = (1.0 - e * e).sqrt();
        let den = 1.0 - e * ea.cos();
        [
            ea.cos() - e,
            s * ea.sin(),
            -ea.sin() / den,
            s * ea.cos() / den,
        ]
    }
    pub fn y0(&self) -> [f64; 4] {
        self.exact(0.0)
    }
}

impl OdeSystem for Kepler {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let r2 = y[0] * y[0] + y[1] * y[1];
        let r3 = r2 * r2.sqrt();
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = -y[0] / r3;
        dy[3] = -y[1] / r3;
    }
}

/// The Arenstorf orbit (HNW I, §II.0, p. 129–130): restricted three-body problem, periodic.
pub struct Arenstorf;

impl Arenstorf {
    pub const MU: f64 = 0.012277471;
    /// Initial state (y1, y2, y1', y2').
    pub const Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.00158510637908252240537862224];
    /// Period.
    pub const T: f64 = 17.0652165601579625588917206249;
}

impl OdeSystem for Arenstorf {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let mu = Self::MU;
        let mup = 1.0 - mu;
        let d1 = ((y[0] + mu).powi(2) + y[1] * y[1]).powf(1.5);
        let d2 = ((y[0] - mup).powi(2) + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = y[0] + 2.0 * y[3] - mup * (y[0] + mu) / d1 - mu * (y[0] - mup) / d2;
        dy[3] = y[1] - 2.0 * y[2] - mup * y[1] / d1 - mu * y[1] / d2;
    }
}

/// y' = A y with A = [[−a, −ω], [ω, −a]]: a decaying rotation,
/// y(t) = e^{−at} (y1 cos ωt − y2 sin ωt, y1 sin ωt + y2 cos ωt).
pub struct Spiral {
    pub a: f64,
    pub w: f64,
}

impl Spiral {
    pub fn exact(&self, t: f64, y0: &[f64]) -> [f64; 2] {
        let d = (-self.a * t).exp();
        let (s, c) = (self.w * t).sin_cos();
        [d * (y0[0] * c - y0[1] * s), d * (y0[0] * s + y0[1] * c)]
    }
}

impl OdeSystem for Spiral {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -self.a * y[0] - self.w * y[1];
        dy[1] = self.w * y[0] - self.a * y[1];
    }
}

/// Van der Pol's equation y1' = y2, y2' = μ(1 − y1²) y2 − y1.
pub struct VanDerPol {
    pub mu: f64,
}

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = self.mu * (1.0 - y[0] * y[0]) * y[1] - y[0];
    }
}

/// The explicit pairs, and their orders.
pub const PAIRS: [(Method, usize); 4] = [
    (Method::Bs32, 3),
    (Method::Dopri54, 5),
    (Method::Tsit54, 5),
    (Method::Dop853, 8),
];

/// Options for a fixed-step run of an adaptive method (or rk4): every step is h.
pub fn fixed(method: Method, h: f64) -> SolverOptions {
    if method.is_fixed_step() {
        SolverOptions {
            method,
            step: Some(h),
            ..Default::default()
        }
    } else {
        SolverOptions {
            method,
            adaptive: false,
            h0: Some(h),
            output: Output::Final,
            ..Default::default()
        }
    }
}

/// Least-squares slope of log(err) against log(h).
pub fn slope(hs: &[f64], errs: &[f64]) -> f64 {
    let x: Vec<f64> = hs.iter().map(|h| h.ln()).collect();
    let y: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Max-norm distance.
pub fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Free fall with bounces: y = (height, velocity), g = 9.81 m/s², restitution e; the event
/// g = height (falling) reverses the velocity times e.
///
/// ```text
/// bounce times from h0 at rest: t₁ = √(2 h0 / g), t_{k+1} = t_k + 2 e^k v₁ / g, v₁ = g t₁
/// ```
pub struct Ball {
    pub e: f64,
}

impl Ball {
    pub const G: f64 = 9.81;
    /// The first `n` bounce times from height h0 at rest: t1 = √(2 h0 / g), then each flight
    /// lasts 2 e v_k / g with the impact speed reduced by e at each bounce.
    pub fn bounce_times(&self, h0: f64, n: usize) -> Vec<f64> {
        let t1 = (2.0 * h0 / Self::G).sqrt();
        let mut times = vec![t1];
        let mut v = Self::G * t1;
        while times.len() < n {
            v *= self.e;
            let last = *times.last().unwrap();
            times.push(last + 2.0 * v / Self::G);
        }
        times
    }
}

impl OdeSystem for Ball {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -Self::G;
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Falling,
            action: EventAction::Continue,
        }
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0];
    }
    fn on_event(&self, _hit: &EventHit, y: &mut [f64]) -> EventAction {
        y[1] *= -self.e;
        EventAction::Continue
    }
}
