//! Wheel slip: how much of each wheel's rotation becomes ground motion.
//!
//! Each wheel's ground speed is `r * omega * (1 - s)`, where the slip `s` is the sum of
//! - a correlated Gaussian process (Ornstein–Uhlenbeck, so the drift it causes does not depend on the
//!   time step) whose standard deviation grows with the body's turn rate, and
//! - occasional slip events (Poisson arrivals while the wheels turn, more frequent when turning) that
//!   take away a random fraction of one wheel's ground speed for a random duration.
//!
//! The error is a fraction of the wheel's speed, so it is proportional to speed and zero at rest.

use crate::error::{SimError, check_non_negative, check_positive};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, StandardNormal};

/// Parameters of the wheel-slip process.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipParams {
    /// Standard deviation of each wheel's fractional ground-speed error when driving straight
    /// (dimensionless; 0.02 = 2 % of wheel speed).
    pub speed_noise: f64,
    /// Additional fractional standard deviation per rad/s of body turn rate (skid steering scrubs).
    pub turn_noise: f64,
    /// Correlation time of the speed error, seconds (> 0).
    pub noise_correlation_time: f64,
    /// Mean slip events per second while the wheels turn (Poisson rate).
    pub event_rate: f64,
    /// Relative increase of the event rate per rad/s of body turn rate.
    pub event_turn_gain: f64,
    /// Mean duration of a slip event, seconds (exponentially distributed).
    pub event_duration: f64,
    /// Largest fraction of a wheel's ground speed lost during an event (uniform in [0, max]).
    pub event_magnitude: f64,
}

impl Default for SlipParams {
    /// An indoor robot on a smooth floor: 0.5 % speed noise (0.2 s correlation), 2 % more per rad/s of
    /// turning, a short slip (up to 15 % of one wheel's speed, ~0.15 s) every ~20 s of driving.
    /// Prawn drifts a few centimetres per 2 m and some decimetres per 10 m with these.
    fn default() -> Self {
        SlipParams {
            speed_noise: 0.005,
            turn_noise: 0.02,
            noise_correlation_time: 0.2,
            event_rate: 0.05,
            event_turn_gain: 1.0,
            event_duration: 0.15,
            event_magnitude: 0.15,
        }
    }
}

impl SlipParams {
    /// No slip at all: ground speed equals wheel speed.
    pub fn none() -> Self {
        SlipParams {
            speed_noise: 0.0,
            turn_noise: 0.0,
            noise_correlation_time: 0.5,
            event_rate: 0.0,
            event_turn_gain: 0.0,
            event_duration: 0.3,
            event_magnitude: 0.0,
        }
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), SimError> {
        check_non_negative("SlipParams.speed_noise", self.speed_noise)?;
        check_non_negative("SlipParams.turn_noise", self.turn_noise)?;
        check_positive("SlipParams.noise_correlation_time", self.noise_correlation_time)?;
        check_non_negative("SlipParams.event_rate", self.event_rate)?;
        check_non_negative("SlipParams.event_turn_gain", self.event_turn_gain)?;
        check_positive("SlipParams.event_duration", self.event_duration)?;
        check_non_negative("SlipParams.event_magnitude", self.event_magnitude)?;
        if self.event_magnitude > 1.0 {
            return Err(crate::error::bad_param(
                "SlipParams.event_magnitude",
                format!("must be at most 1, got {}", self.event_magnitude),
            ));
        }
        Ok(())
    }
}

/// The state of the slip process of one robot's two wheels.
#[derive(Debug, Clone)]
pub struct SlipState {
    params: SlipParams,
    /// Unit-variance OU state per wheel (left, right).
    ou: [f64; 2],
    /// Remaining time and lost fraction of the current event per wheel.
    event: [(f64, f64); 2],
}

impl SlipState {
    /// A slip process at rest.
    pub fn new(params: SlipParams) -> Self {
        SlipState { params, ou: [0.0; 2], event: [(0.0, 0.0); 2] }
    }

    /// The parameters.
    pub fn params(&self) -> &SlipParams {
        &self.params
    }

    /// True while a slip event is under way on either wheel.
    pub fn in_event(&self) -> bool {
        self.event.iter().any(|e| e.0 > 0.0)
    }

    /// Advances by `dt` and returns the fraction of each wheel's speed lost, `(s_left, s_right)`.
    ///
    /// `wheel_speeds` are the wheels' rim speeds (m/s) and `turn_rate` the commanded body turn rate.
    pub fn step(&mut self, rng: &mut ChaCha8Rng, dt: f64, wheel_speeds: [f64; 2], turn_rate: f64) -> [f64; 2] {
        let p = &self.params;
        let moving = wheel_speeds.iter().any(|v| v.abs() > 1e-6);
        let a = (-dt / p.noise_correlation_time).exp();
        let b = (1.0 - a * a).sqrt();
        let sigma = p.speed_noise + p.turn_noise * turn_rate.abs();
        let mut s = [0.0; 2];
        for ((sw, ou), e) in s.iter_mut().zip(&mut self.ou).zip(&mut self.event) {
            if sigma > 0.0 {
                let n: f64 = StandardNormal.sample(rng);
                *ou = a * *ou + b * n;
            }
            if e.0 > 0.0 {
                e.0 -= dt;
            } else {
                e.1 = 0.0;
            }
            *sw = sigma * *ou + if e.0 > 0.0 { e.1 } else { 0.0 };
        }
        if moving && p.event_rate > 0.0 && p.event_magnitude > 0.0 {
            let rate = p.event_rate * (1.0 + p.event_turn_gain * turn_rate.abs());
            if rng.random::<f64>() < 1.0 - (-rate * dt).exp() {
                let w = usize::from(rng.random::<bool>());
                let dur = Exp::new(1.0 / p.event_duration).map(|d| d.sample(rng)).unwrap_or(p.event_duration);
                let mag = rng.random::<f64>() * p.event_magnitude;
                self.event[w] = (dur, mag);
                s[w] += mag;
            }
        }
        // A wheel never drives the ground faster than twice its rim speed nor backwards.
        s.map(|x| x.clamp(-1.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn no_slip_means_no_loss() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut s = SlipState::new(SlipParams::none());
        for _ in 0..1000 {
            assert_eq!(s.step(&mut rng, 0.01, [0.5, 0.5], 0.3), [0.0, 0.0]);
        }
    }

    #[test]
    fn noise_has_the_configured_spread() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let p = SlipParams { event_rate: 0.0, ..SlipParams::default() };
        let mut s = SlipState::new(p);
        let v: Vec<f64> = (0..200_000).map(|_| s.step(&mut rng, 0.01, [0.5, 0.5], 0.0)[0]).collect();
        let var = v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
        assert!((var.sqrt() - p.speed_noise).abs() < 0.3 * p.speed_noise, "{}", var.sqrt());
    }

    #[test]
    fn events_happen_at_about_the_rate_and_more_when_turning() {
        let p = SlipParams {
            speed_noise: 0.0,
            turn_noise: 0.0,
            event_rate: 1.0,
            event_duration: 0.001,
            ..SlipParams::default()
        };
        let count = |turn: f64| {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let mut s = SlipState::new(p);
            (0..100_000).filter(|_| s.step(&mut rng, 0.01, [0.5, 0.5], turn).iter().any(|&x| x > 0.0)).count()
        };
        let straight = count(0.0);
        assert!((800..1200).contains(&straight), "{straight}");
        assert!(count(1.0) > straight * 3 / 2);
    }

    #[test]
    fn validation_rejects_bad_values() {
        assert!(SlipParams::default().validate().is_ok());
        let bad = SlipParams { speed_noise: -0.1, ..SlipParams::default() };
        assert!(bad.validate().is_err());
        let bad = SlipParams { noise_correlation_time: 0.0, ..SlipParams::default() };
        assert!(bad.validate().is_err());
    }
}
