//! What a Hesai packet's fields must agree on beyond its format, checked before it is decoded:
//! a dual-return packet's pairs of blocks (one firing each) share an azimuth, and the block
//! azimuths advance from firing to firing by what the motor speed and the model's firing time
//! give. A packet that contradicts itself is refused naming both values
//! ([`PacketError::DualPair`], [`PacketError::FiringStep`]): a rotor that does not turn,
//! dual-return data under a single-return mode byte or the reverse, another protocol's or
//! another operational state's packets relabelled.

use crate::error::PacketError;
use crate::sweep::{wrap_azimuth, AZIMUTH_UNITS};

/// Slack on the step from firing to firing, 0.01 degree, beside a quarter of the step: the
/// azimuth's rounding and a motor speed a few rpm off its reading.
const STEP_SLACK: f64 = 2.0;

/// The azimuth step from one firing to the next, 0.01 degree, at `rpm` with firings
/// `firing_ns` apart.
pub(super) fn firing_step(rpm: u16, firing_ns: i64) -> f64 {
    f64::from(rpm) * f64::from(AZIMUTH_UNITS) / 60.0 * firing_ns as f64 * 1e-9
}

/// Checks the azimuths of a packet of `blocks` blocks (`azimuth(k)`, 0.01 degree) in a mode of
/// `returns` blocks a firing, at `rpm` with firings `firing_ns` apart. A motor speed of 0 (not
/// read) only asks that the azimuth advance.
pub(super) fn azimuths_agree(
    azimuth: impl Fn(usize) -> u16,
    blocks: usize,
    returns: usize,
    rpm: u16,
    firing_ns: i64,
) -> Result<(), PacketError> {
    let returns = returns.max(1);
    for k in (0..blocks).step_by(returns) {
        for other in k + 1..(k + returns).min(blocks) {
            if azimuth(other) != azimuth(k) {
                return Err(PacketError::DualPair {
                    first: azimuth(k),
                    second: azimuth(other),
                });
            }
        }
    }
    let expected = firing_step(rpm, firing_ns);
    for k in (returns..blocks).step_by(returns) {
        let step = wrap_azimuth(i32::from(azimuth(k)) - i32::from(azimuth(k - returns)));
        let off = (f64::from(step) - expected).abs() > expected / 4.0 + STEP_SLACK;
        if step == 0 || (rpm > 0 && off) {
            return Err(PacketError::FiringStep {
                step: step as u16,
                expected: libm::round(expected) as u16,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firings_advance_by_the_motor_speed_and_pairs_share_an_azimuth() {
        // XT32 at 600 rpm: 50 us firings, 0.18 degree apart.
        assert!((firing_step(600, 50_000) - 18.0).abs() < 1e-9);
        let at = |a: &'static [u16]| move |k: usize| a[k];
        assert_eq!(
            azimuths_agree(at(&[100, 118, 136, 154]), 4, 1, 600, 50_000),
            Ok(())
        );
        // Across 360 degrees.
        assert_eq!(
            azimuths_agree(at(&[35_990, 8, 26, 44]), 4, 1, 600, 50_000),
            Ok(())
        );
        // A rotor that does not turn, a step four times the motor's.
        assert_eq!(
            azimuths_agree(at(&[100, 100, 100, 100]), 4, 1, 600, 50_000),
            Err(PacketError::FiringStep {
                step: 0,
                expected: 18
            })
        );
        assert_eq!(
            azimuths_agree(at(&[100, 172, 244, 316]), 4, 1, 600, 50_000),
            Err(PacketError::FiringStep {
                step: 72,
                expected: 18
            })
        );
        // Dual: pairs share the azimuth, and the pairs advance.
        assert_eq!(
            azimuths_agree(at(&[100, 100, 118, 118]), 4, 2, 600, 50_000),
            Ok(())
        );
        assert_eq!(
            azimuths_agree(at(&[100, 118, 136, 154]), 4, 2, 600, 50_000),
            Err(PacketError::DualPair {
                first: 100,
                second: 118
            })
        );
        // No motor speed read: only an advance is asked for.
        assert_eq!(
            azimuths_agree(at(&[100, 172, 244, 316]), 4, 1, 0, 50_000),
            Ok(())
        );
        assert!(azimuths_agree(at(&[100, 100, 118, 118]), 4, 1, 0, 50_000).is_err());
    }
}
