//! The sensor's path: a smooth parametric trajectory whose pose is exact at any instant.
//!
//! A vehicle follows a planar route given by its curvature over arc length: straights joined by
//! turns whose curvature ramps in and out with a quintic smoothstep (so yaw rate and yaw
//! acceleration are continuous). Heading is the closed-form integral of curvature; position is
//! the integral of heading, evaluated with 4-point Gauss-Legendre between metre knots and split
//! at piece boundaries (accurate to rounding). Speed is a sum of sinusoids in time, eased in
//! from a standing start, whose integral (arc length) is closed form, so `s(t)` needs no ODE.
//! Urban turns are laid out wide enough for the speed the vehicle will have there (bounded
//! lateral and yaw acceleration); `fast` turns are not (about 1 rad/s). Body roll follows lateral
//! acceleration, pitch follows longitudinal acceleration, both saturating smoothly, plus a small
//! road wobble. Raycasting and ground truth both call [`Trajectory::pose`], so they agree
//! exactly.

use crate::profile::Profile;
use crate::rng::{Purpose, Stream};
use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3};

/// A rigid pose with a rotation matrix (world from sensor).
pub type PoseM = IsometryMatrix3<f64>;

const GL_NODES: [f64; 4] = [
    -0.861_136_311_594_052_6,
    -0.339_981_043_584_856_3,
    0.339_981_043_584_856_3,
    0.861_136_311_594_052_6,
];
const GL_WEIGHTS: [f64; 4] = [
    0.347_854_845_137_453_9,
    0.652_145_154_862_546_1,
    0.652_145_154_862_546_1,
    0.347_854_845_137_453_9,
];

/// Spacing of the precomputed position knots (m).
const KNOT: f64 = 1.0;
/// Route length before the start (m): the sensor sees about `r_max` behind it.
pub const ROUTE_BEFORE_START: f64 = 200.0;
/// Route length after the last pose (m), for the same reason.
pub const ROUTE_AFTER_END: f64 = 200.0;
/// Largest lateral acceleration in urban turns (m/s^2).
const URBAN_LATERAL_ACCEL: f64 = 3.5;
/// Largest yaw acceleration in urban turns (rad/s^2).
const URBAN_YAW_ACCEL: f64 = 1.0;

/// Quintic smoothstep `6u^5 - 15u^4 + 10u^3`: zero first and second derivative at both ends.
#[inline]
fn smootherstep(u: f64) -> f64 {
    u * u * u * (u * (6.0 * u - 15.0) + 10.0)
}

/// `integral_0^u smootherstep = u^6 - 3u^5 + 2.5u^4` (equals 1/2 at `u = 1`).
#[inline]
fn smootherstep_integral(u: f64) -> f64 {
    let u2 = u * u;
    u2 * u2 * (u * (u - 3.0) + 2.5)
}

/// One piece of the curvature profile, over `[s0, s0 + len]`: curvature eases from `k0` to `k1`.
#[derive(Clone, Copy, Debug)]
struct Piece {
    s0: f64,
    len: f64,
    k0: f64,
    k1: f64,
    psi0: f64,
}

impl Piece {
    fn end(&self) -> f64 {
        self.s0 + self.len
    }

    fn u(&self, s: f64) -> f64 {
        ((s - self.s0) / self.len).clamp(0.0, 1.0)
    }

    fn curvature(&self, s: f64) -> f64 {
        self.k0 + (self.k1 - self.k0) * smootherstep(self.u(s))
    }

    /// Exact only inside the piece, or anywhere for a straight (which is how the route begins
    /// and ends, so extrapolation past either end stays exact).
    fn heading(&self, s: f64) -> f64 {
        self.psi0
            + self.k0 * (s - self.s0)
            + (self.k1 - self.k0) * self.len * smootherstep_integral(self.u(s))
    }
}

/// Appends pieces while tracking arc length and heading.
struct Builder {
    pieces: Vec<Piece>,
    s: f64,
    psi: f64,
}

impl Builder {
    fn new(s_min: f64) -> Self {
        Self {
            pieces: Vec::new(),
            s: s_min,
            psi: 0.0,
        }
    }

    fn push(&mut self, len: f64, k0: f64, k1: f64) {
        if len <= 0.0 {
            return;
        }
        let p = Piece {
            s0: self.s,
            len,
            k0,
            k1,
            psi0: self.psi,
        };
        self.psi = p.heading(p.end());
        self.s = p.end();
        self.pieces.push(p);
    }

    fn straight(&mut self, len: f64) {
        self.push(len, 0.0, 0.0);
    }

    /// A turn by `angle` (rad, positive left) at radius `radius`, easing in and out over
    /// `transition` metres each.
    fn turn(&mut self, angle: f64, radius: f64, transition: f64) {
        let k = angle.signum() / radius;
        let arc = angle.abs() * radius;
        // Each ramp contributes half its length at full curvature.
        let ramp = transition.min(arc);
        self.push(ramp, 0.0, k);
        self.push(arc - ramp, k, k);
        self.push(ramp, k, 0.0);
    }
}

/// A planar route: curvature pieces plus position knots every metre.
#[derive(Clone, Debug)]
pub struct Route {
    pieces: Vec<Piece>,
    knots: Vec<[f64; 2]>,
    s_min: f64,
}

impl Route {
    fn from_pieces(pieces: Vec<Piece>) -> Self {
        let s_min = pieces[0].s0;
        let end = pieces[pieces.len() - 1].end();
        let n = ((end - s_min) / KNOT).floor() as usize + 1;
        let mut route = Self {
            pieces,
            knots: Vec::with_capacity(n.max(2)),
            s_min,
        };
        let mut p = [s_min, 0.0];
        route.knots.push(p);
        for j in 0..n.max(2) - 1 {
            let a = s_min + j as f64 * KNOT;
            let d = route.integrate(a, a + KNOT);
            p = [p[0] + d[0], p[1] + d[1]];
            route.knots.push(p);
        }
        route
    }

    /// Generates the route of `profile` long enough for `length` metres of driving at
    /// `speed` (urban turns widen with the speed the vehicle will have there).
    fn generate(profile: Profile, seed: u64, length: f64, speed: &Speed) -> Self {
        let mut rng = Stream::new(seed, Purpose::Route);
        let mut b = Builder::new(-ROUTE_BEFORE_START);
        let end = length + ROUTE_AFTER_END;
        match profile {
            Profile::Urban
            | Profile::Plane
            | Profile::Field
            | Profile::Handheld
            | Profile::Drone => {
                b.straight(ROUTE_BEFORE_START + rng.range(30.0, 80.0));
                while b.s < end {
                    let angle = if rng.chance(0.6) {
                        core::f64::consts::FRAC_PI_2
                    } else {
                        rng.range(0.25, 1.0)
                    } * rng.sign();
                    // Keep lateral acceleration v^2/R and yaw acceleration (about
                    // v^2 kappa 1.875/L at the ramp's steepest) at what a car does in town.
                    let t = speed.time_at(b.s);
                    let v = speed.max_speed(t, t + 8.0);
                    let radius = rng.range(10.0, 30.0).max(v * v / URBAN_LATERAL_ACCEL);
                    let ramp = rng
                        .range(6.0, 15.0)
                        .max(1.875 * v * v / (radius * URBAN_YAW_ACCEL));
                    b.turn(angle, radius, ramp);
                    b.straight(rng.range(40.0, 180.0));
                }
            }
            Profile::Suburban | Profile::Forest => {
                // Long streets joined by turns laid out, as in town, for the speed there.
                b.straight(ROUTE_BEFORE_START + rng.range(100.0, 300.0));
                while b.s < end {
                    let angle = if rng.chance(0.6) {
                        core::f64::consts::FRAC_PI_2
                    } else {
                        rng.range(0.2, 0.8)
                    } * rng.sign();
                    let t = speed.time_at(b.s);
                    let v = speed.max_speed(t, t + 8.0);
                    let radius = rng.range(30.0, 80.0).max(v * v / URBAN_LATERAL_ACCEL);
                    let ramp = rng
                        .range(10.0, 20.0)
                        .max(1.875 * v * v / (radius * URBAN_YAW_ACCEL));
                    b.turn(angle, radius, ramp);
                    b.straight(rng.range(150.0, 400.0));
                }
            }
            Profile::Fast => {
                b.straight(ROUTE_BEFORE_START + rng.range(40.0, 80.0));
                while b.s < end {
                    let angle = if rng.chance(0.5) {
                        core::f64::consts::FRAC_PI_2
                    } else {
                        rng.range(0.5, 1.2)
                    } * rng.sign();
                    b.turn(angle, rng.range(20.0, 30.0), rng.range(8.0, 15.0));
                    // Back-to-back turns (chicanes) reverse the yaw rate abruptly.
                    let straight = if rng.chance(0.3) {
                        0.0
                    } else {
                        rng.range(30.0, 120.0)
                    };
                    b.straight(straight);
                }
            }
            Profile::Warehouse => {
                // Aisles joined by tight right-angle turns into cross aisles.
                b.straight(ROUTE_BEFORE_START + rng.range(10.0, 30.0));
                while b.s < end {
                    let angle = core::f64::consts::FRAC_PI_2 * rng.sign();
                    b.turn(angle, rng.range(3.0, 5.0), rng.range(1.5, 3.0));
                    b.straight(rng.range(20.0, 80.0));
                }
            }
            Profile::Corridor | Profile::Tunnel => {
                // A gentle weave: each S-bend is mirrored by the next, so the lateral offset
                // returns exactly to zero and the route stays on the corridor's axis.
                b.straight(ROUTE_BEFORE_START + 30.0);
                while b.s < end {
                    let angle = rng.range(0.04, 0.1) * rng.sign();
                    let radius = rng.range(50.0, 90.0);
                    let tr = 4.0;
                    let gap = rng.range(20.0, 60.0);
                    b.turn(angle, radius, tr);
                    b.turn(-angle, radius, tr);
                    b.straight(gap);
                    b.turn(-angle, radius, tr);
                    b.turn(angle, radius, tr);
                    b.straight(gap);
                }
            }
        }
        // A long final straight: extrapolation past the last knot stays exact.
        b.straight(ROUTE_AFTER_END + 100.0);
        Self::from_pieces(b.pieces)
    }

    fn piece(&self, s: f64) -> &Piece {
        let i = self.pieces.partition_point(|p| p.s0 <= s);
        &self.pieces[i.saturating_sub(1)]
    }

    /// Curvature at arc length `s` (1/m, positive left).
    pub fn curvature(&self, s: f64) -> f64 {
        self.piece(s).curvature(s)
    }

    /// Heading at arc length `s` (rad, from the world x axis).
    pub fn heading(&self, s: f64) -> f64 {
        self.piece(s).heading(s)
    }

    /// `integral_a^b (cos psi, sin psi) ds`, split at piece boundaries so each part is smooth.
    fn integrate(&self, a: f64, b: f64) -> [f64; 2] {
        let mut acc = [0.0, 0.0];
        let mut i = self.pieces.partition_point(|p| p.s0 <= a).saturating_sub(1);
        let mut lo = a;
        while lo < b {
            let p = &self.pieces[i];
            let last = i + 1 == self.pieces.len();
            let hi = if last { b } else { p.end().min(b) };
            if hi > lo {
                let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                for (x, w) in GL_NODES.iter().zip(GL_WEIGHTS) {
                    let psi = p.heading(mid + half * x);
                    acc[0] += w * half * libm::cos(psi);
                    acc[1] += w * half * libm::sin(psi);
                }
            }
            lo = hi;
            if last {
                break;
            }
            i += 1;
        }
        acc
    }

    /// Position at arc length `s` (m). Past either end the route continues straight.
    pub fn position(&self, s: f64) -> [f64; 2] {
        let last = self.knots.len() - 1;
        let s_last = self.s_min + last as f64 * KNOT;
        let (j, s_j) = if s <= self.s_min {
            // Before the start the first piece is a straight: step back along it.
            let psi = self.pieces[0].psi0;
            let k = self.knots[0];
            return [
                k[0] + (s - self.s_min) * libm::cos(psi),
                k[1] + (s - self.s_min) * libm::sin(psi),
            ];
        } else if s >= s_last {
            (last, s_last)
        } else {
            let j = (((s - self.s_min) / KNOT) as usize).min(last);
            (j, self.s_min + j as f64 * KNOT)
        };
        let d = self.integrate(s_j, s);
        [self.knots[j][0] + d[0], self.knots[j][1] + d[1]]
    }

    /// Arc length covered by the knots (for scene generation).
    pub fn knot_span(&self) -> (f64, f64) {
        (
            self.s_min,
            self.s_min + (self.knots.len() - 1) as f64 * KNOT,
        )
    }
}

/// `a * sin(w t + phi)`.
#[derive(Clone, Copy, Debug)]
struct Wave {
    amp: f64,
    omega: f64,
    phase: f64,
}

impl Wave {
    fn random(rng: &mut Stream, amp: f64, period: (f64, f64)) -> Self {
        Self {
            amp,
            omega: core::f64::consts::TAU / rng.range(period.0, period.1),
            phase: rng.range(0.0, core::f64::consts::TAU),
        }
    }

    fn at(&self, t: f64) -> f64 {
        self.amp * libm::sin(self.omega * t + self.phase)
    }

    fn rate(&self, t: f64) -> f64 {
        self.amp * self.omega * libm::cos(self.omega * t + self.phase)
    }

    /// `integral_0^t`.
    fn integral(&self, t: f64) -> f64 {
        self.amp / self.omega * (libm::cos(self.phase) - libm::cos(self.omega * t + self.phase))
    }
}

/// A complex number, just enough for the launch integral (kept on `libm` for portable bits).
#[derive(Clone, Copy, Debug)]
struct C(f64, f64);

impl C {
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    fn sub(self, o: C) -> C {
        C(self.0 - o.0, self.1 - o.1)
    }
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn scale(self, k: f64) -> C {
        C(self.0 * k, self.1 * k)
    }
}

/// Speed over time: a cruise profile `mid + sum of waves` (amplitudes summing to
/// `(hi - lo) / 2`, so it stays in `[lo, hi]`) times a launch envelope
/// `h(t) = 1 - e^(-t/tau) (1 + t/tau)` that starts the vehicle from rest with zero
/// acceleration. Arc length is the closed-form integral of the product.
#[derive(Clone, Debug)]
struct Speed {
    mid: f64,
    waves: [Wave; 3],
    /// `1 / tau` of the launch (1/s); 0 for a flying start.
    launch: f64,
}

impl Speed {
    fn new(rng: &mut Stream, lo: f64, hi: f64, launch_tau: f64) -> Self {
        let w = [
            rng.range(0.2, 1.0),
            rng.range(0.2, 1.0),
            rng.range(0.2, 1.0),
        ];
        let total: f64 = w.iter().sum();
        let half = 0.5 * (hi - lo);
        let periods = [(20.0, 40.0), (8.0, 20.0), (4.0, 8.0)];
        let mut waves = [Wave {
            amp: 0.0,
            omega: 1.0,
            phase: 0.0,
        }; 3];
        for (k, wave) in waves.iter_mut().enumerate() {
            *wave = Wave::random(rng, half * w[k] / total, periods[k]);
        }
        Self {
            mid: 0.5 * (lo + hi),
            waves,
            launch: if launch_tau > 0.0 {
                1.0 / launch_tau
            } else {
                0.0
            },
        }
    }

    fn cruise(&self, t: f64) -> f64 {
        self.mid + self.waves.iter().map(|w| w.at(t)).sum::<f64>()
    }

    /// The launch envelope and its derivative.
    fn envelope(&self, t: f64) -> (f64, f64) {
        if self.launch == 0.0 {
            return (1.0, 0.0);
        }
        let l = self.launch;
        let e = libm::exp(-l * t);
        (1.0 - e * (1.0 + l * t), l * l * t * e)
    }

    fn speed(&self, t: f64) -> f64 {
        if t <= 0.0 && self.launch > 0.0 {
            return 0.0;
        }
        self.cruise(t) * self.envelope(t).0
    }

    fn accel(&self, t: f64) -> f64 {
        if t <= 0.0 && self.launch > 0.0 {
            return 0.0;
        }
        let (h, dh) = self.envelope(t);
        let rate: f64 = self.waves.iter().map(|w| w.rate(t)).sum();
        rate * h + self.cruise(t) * dh
    }

    /// The time at which arc length `s` is reached (bisection; 0 for `s <= 0`).
    fn time_at(&self, s: f64) -> f64 {
        if s <= 0.0 {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        while self.arc_length(hi) < s && hi < 1e7 {
            hi *= 2.0;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.arc_length(mid) < s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// The largest speed over `[t0, t1]`, sampled every 0.1 s.
    fn max_speed(&self, t0: f64, t1: f64) -> f64 {
        let n = ((t1 - t0) / 0.1).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| self.speed(t0 + (t1 - t0) * i as f64 / n as f64))
            .fold(0.0, f64::max)
    }

    /// `integral_0^t speed`: the cruise integral minus `integral_0^t cruise(u) g(u) du` with
    /// `g = 1 - h = e^(-lu) (1 + lu)`, in closed form (complex exponentials for the waves).
    fn arc_length(&self, t: f64) -> f64 {
        let cruise = self.mid * t + self.waves.iter().map(|w| w.integral(t)).sum::<f64>();
        if self.launch == 0.0 {
            return cruise;
        }
        if t <= 0.0 {
            return 0.0;
        }
        let l = self.launch;
        let e = libm::exp(-l * t);
        let mut lost = self.mid * (2.0 * (1.0 - e) / l - t * e);
        for w in &self.waves {
            // integral_0^t e^(zu) (1 + l u) du with z = -l + i omega, then Im(e^(i phi) .).
            let z = C(-l, w.omega);
            let big = C(e * libm::cos(w.omega * t), e * libm::sin(w.omega * t));
            let em1 = big.sub(C(1.0, 0.0));
            let first = em1.div(z);
            let second = big.scale(t).div(z).sub(em1.div(z.mul(z)));
            let j = first.add(second.scale(l));
            let rot = C(libm::cos(w.phase), libm::sin(w.phase));
            lost += w.amp * rot.mul(j).1;
        }
        cruise - lost
    }
}

/// How a profile moves: speed band, launch, body motion, sensor height.
#[derive(Clone, Copy, Debug)]
struct MotionParams {
    speed: (f64, f64),
    /// Time constant of the start from rest (s); the vehicle is at 95% of its cruise speed
    /// after about 4.7 of them.
    launch_tau: f64,
    /// Body roll per m/s^2 of lateral acceleration (rad s^2/m) and its saturation (rad).
    roll_gain: f64,
    roll_max: f64,
    /// Body pitch per m/s^2 of longitudinal acceleration and its saturation.
    pitch_gain: f64,
    pitch_max: f64,
    /// Road undulation (periods 3-8 s) and suspension vibration (0.6-1 s) amplitudes, for
    /// roll and pitch (rad) and height (m).
    wobble: [[f64; 2]; 3],
    height: f64,
    /// Swings about the path (hand-held or flying): for yaw, pitch and roll (rad) and height
    /// (m), a slow and a fast wave, each `(amplitude, shortest period, longest period)` (s).
    swing: [[(f64, f64, f64); 2]; 4],
}

impl MotionParams {
    fn of(profile: Profile) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let car = Self {
            speed: (5.0, 15.0),
            launch_tau: 1.5,
            roll_gain: 0.4 * deg,
            roll_max: 3.0 * deg,
            pitch_gain: 0.5 * deg,
            pitch_max: 2.0 * deg,
            wobble: [
                [0.25 * deg, 0.04 * deg],
                [0.25 * deg, 0.04 * deg],
                [0.02, 0.004],
            ],
            height: 1.73,
            swing: [[(0.0, 1.0, 1.0); 2]; 4],
        };
        match profile {
            Profile::Urban | Profile::Plane | Profile::Field => car,
            Profile::Fast => Self {
                speed: (20.0, 30.0),
                launch_tau: 1.0,
                ..car
            },
            Profile::Corridor | Profile::Tunnel => Self {
                speed: (3.0, 8.0),
                ..car
            },
            Profile::Warehouse => Self {
                speed: (1.5, 3.0),
                ..car
            },
            Profile::Forest => Self {
                speed: (8.0, 12.0),
                launch_tau: 2.0,
                ..car
            },
            Profile::Suburban => Self {
                speed: (15.5, 18.5),
                launch_tau: 2.0,
                ..car
            },
            // Walking: no body roll or pitch from the path, but the walker looks around and
            // the hand swings and bobs with the steps (about 2 a second).
            Profile::Handheld => Self {
                speed: (1.0, 1.8),
                launch_tau: 1.0,
                roll_gain: 0.0,
                pitch_gain: 0.0,
                wobble: [[0.0; 2]; 3],
                height: 1.4,
                swing: [
                    [(0.5, 2.5, 4.5), (0.12, 0.8, 1.5)],
                    [(0.15, 2.0, 5.0), (0.04, 0.45, 0.6)],
                    [(0.1, 2.0, 5.0), (0.03, 0.45, 0.6)],
                    [(0.05, 3.0, 6.0), (0.025, 0.45, 0.6)],
                ],
                ..car
            },
            // A multirotor banks into turns and pitches to accelerate, looks around fast and
            // climbs and descends.
            Profile::Drone => Self {
                speed: (3.0, 10.0),
                launch_tau: 2.0,
                roll_gain: 2.5 * deg,
                roll_max: 20.0 * deg,
                pitch_gain: 2.5 * deg,
                pitch_max: 15.0 * deg,
                wobble: [[0.0; 2]; 3],
                height: 8.0,
                swing: [
                    [(1.0, 4.0, 8.0), (0.25, 1.0, 2.0)],
                    [(0.08, 2.0, 4.0), (0.02, 0.3, 0.6)],
                    [(0.08, 2.0, 4.0), (0.02, 0.3, 0.6)],
                    [(3.0, 10.0, 20.0), (0.2, 2.0, 4.0)],
                ],
            },
        }
    }
}

/// The sensor's pose at any time: route, speed, body attitude.
#[derive(Clone, Debug)]
pub struct Trajectory {
    route: Route,
    speed: Speed,
    motion: MotionParams,
    roll: [Wave; 2],
    pitch: [Wave; 2],
    bounce: [Wave; 2],
    /// Swings in yaw, pitch, roll and height, if the profile has them.
    swing: Option<[[Wave; 2]; 4]>,
    /// Seconds of the drive before trajectory time 0.
    lead_in: f64,
    /// Driven backwards along the route, beside it (a revisit); `None`: along it.
    reverse: Option<Reverse>,
}

/// A route driven from its end towards its start, beside it.
#[derive(Clone, Copy, Debug)]
struct Reverse {
    /// Route arc length at drive time 0 (m).
    start: f64,
    /// Offset from the route, positive left of its own direction (m).
    lateral: f64,
}

impl Trajectory {
    /// The trajectory of `profile` under `seed`, with route for `duration` seconds of driving.
    pub fn generate(profile: Profile, seed: u64, duration: f64) -> Self {
        Self::generate_after(profile, seed, 0.0, duration)
    }

    /// As [`Trajectory::generate`], but time 0 is `lead_in` seconds into the drive: the same
    /// route and motion, entered moving.
    pub fn generate_after(profile: Profile, seed: u64, lead_in: f64, duration: f64) -> Self {
        let motion = MotionParams::of(profile);
        let mut rng = Stream::new(seed, Purpose::Motion);
        let speed = Speed::new(&mut rng, motion.speed.0, motion.speed.1, motion.launch_tau);
        let [wr, wp, wz] = motion.wobble;
        let mut waves = |amp: [f64; 2]| {
            [
                Wave::random(&mut rng, amp[0], (3.0, 8.0)),
                Wave::random(&mut rng, amp[1], (0.6, 1.0)),
            ]
        };
        let (roll, pitch, bounce) = (waves(wr), waves(wp), waves(wz));
        // Speed never exceeds the band's top, so this covers the whole run.
        let length = motion.speed.1 * (lead_in + duration.max(0.0));
        let route = Route::generate(profile, seed, length, &speed);
        // Drawn from a stream of their own, so the cars' trajectories are unchanged.
        let mut rng = Stream::new(seed, Purpose::Swing);
        let swing = profile.swings().then(|| {
            motion
                .swing
                .map(|axis| axis.map(|(amp, lo, hi)| Wave::random(&mut rng, amp, (lo, hi))))
        });
        Self {
            route,
            speed,
            motion,
            roll,
            pitch,
            bounce,
            swing,
            lead_in,
            reverse: None,
        }
    }

    /// The route followed.
    pub fn route(&self) -> &Route {
        &self.route
    }

    /// Arc length driven after `t` seconds (from time 0, the lead-in's not counted).
    pub fn arc_length(&self, t: f64) -> f64 {
        if self.lead_in == 0.0 {
            return self.speed.arc_length(t);
        }
        self.speed.arc_length(self.drive_time(t)) - self.speed.arc_length(self.lead_in)
    }

    /// Speed at `t` (m/s).
    pub fn speed(&self, t: f64) -> f64 {
        self.speed.speed(self.drive_time(t))
    }

    /// Seconds since the drive's start at trajectory time `t` (`t` itself, bit for bit,
    /// without a lead-in).
    fn drive_time(&self, t: f64) -> f64 {
        if self.lead_in == 0.0 {
            t
        } else {
            self.lead_in + t
        }
    }

    /// The route's arc length under the sensor at `t` (m; it falls on a revisit).
    pub fn route_arc(&self, t: f64) -> f64 {
        self.route_arc_at_drive_time(self.drive_time(t))
    }

    fn route_arc_at_drive_time(&self, t: f64) -> f64 {
        match &self.reverse {
            None => self.speed.arc_length(t),
            Some(r) => r.start - self.speed.arc_length(t),
        }
    }

    /// Roll, pitch and yaw (rad) and position (m) at `t`: the pose's parameters.
    pub fn state(&self, t: f64) -> ([f64; 3], [f64; 3]) {
        let t = self.drive_time(t);
        let m = &self.motion;
        let s = self.route_arc_at_drive_time(t);
        let v = self.speed.speed(t);
        // Driven backwards, a left turn of the route is a right turn of the vehicle.
        let curvature = match self.reverse {
            None => self.route.curvature(s),
            Some(_) => -self.route.curvature(s),
        };
        let lateral = v * v * curvature;
        let longitudinal = self.speed.accel(t);
        let saturate = |gain: f64, max: f64, a: f64| max * libm::tanh(gain * a / max);
        let sum = |w: &[Wave; 2]| w[0].at(t) + w[1].at(t);
        // The body rolls out of a turn and pitches nose-up when accelerating (about +y, a
        // positive pitch is nose-down).
        let mut roll = -saturate(m.roll_gain, m.roll_max, lateral) + sum(&self.roll);
        let mut pitch = -saturate(m.pitch_gain, m.pitch_max, longitudinal) + sum(&self.pitch);
        let mut yaw = self.route.heading(s);
        let [mut x, mut y] = self.route.position(s);
        if let Some(r) = &self.reverse {
            // A curve offset from the route is parallel to it: same tangent, other way.
            x -= libm::sin(yaw) * r.lateral;
            y += libm::cos(yaw) * r.lateral;
            yaw += core::f64::consts::PI;
        }
        let mut z = m.height + sum(&self.bounce);
        if let Some([sy, sp, sr, sz]) = &self.swing {
            yaw += sum(sy);
            pitch += sum(sp);
            roll += sum(sr);
            z += sum(sz);
        }
        ([roll, pitch, yaw], [x, y, z])
    }

    /// World-from-sensor pose at time `t` (s since the start of the first sweep).
    pub fn pose(&self, t: f64) -> PoseM {
        let ([roll, pitch, yaw], p) = self.state(t);
        IsometryMatrix3::from_parts(
            Translation3::new(p[0], p[1], p[2]),
            rotation_zyx(roll, pitch, yaw),
        )
    }
}

/// `Rz(yaw) Ry(pitch) Rx(roll)` (rad), on `libm` so the bits are the same everywhere.
pub fn rotation_zyx(roll: f64, pitch: f64, yaw: f64) -> Rotation3<f64> {
    let (sr, cr) = (libm::sin(roll), libm::cos(roll));
    let (sp, cp) = (libm::sin(pitch), libm::cos(pitch));
    let (sy, cy) = (libm::sin(yaw), libm::cos(yaw));
    #[rustfmt::skip]
    let r = Matrix3::new(
        cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
        -sp,     cp * sr,                cp * cr,
    );
    Rotation3::from_matrix_unchecked(r)
}

mod revisit;
#[cfg(test)]
mod tests;
