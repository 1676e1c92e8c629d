//! The `imu` profile: the `tiny` drive with its IMU samples (`kiss-odom simulate --imu-rate`),
//! each frame predicted and deskewed with the gyroscope's rotation (`GyroPrior`), as
//! `kiss-odom run --imu auto` does on the host. The samples are embedded as `build.rs` cut them
//! per frame; each frame's are converted into a fixed buffer the caller owns.

use crate::frames;
use crate::profile::{Codec, Scalar};
use kiss_odom_core::{GyroPrior, ImuConfig, ImuSample, Odometry, Prior, Real, Storage};

/// Samples a frame may bring: 0.16 s at 400 Hz (the first frame brings 0.2 s at the drive's
/// 200 Hz); more are cut, and the prior then reports the gap.
const CAPACITY: usize = 64;

#[repr(C, align(8))]
struct Aligned<B: ?Sized>(B);

/// 7 f64 a sample: time, gyro x y z, accel x y z.
static BYTES: &Aligned<[u8]> = &Aligned(*include_bytes!(concat!(env!("OUT_DIR"), "/imu.bin")));

/// The prior and the buffer it reads a frame's samples from.
pub struct Imu {
    prior: GyroPrior<Scalar>,
    buf: [ImuSample<Scalar>; CAPACITY],
    n: usize,
    used: Prior,
    residual: Option<Scalar>,
}

impl Imu {
    /// The simulator's IMU: axes and clock the LiDAR's (its lever arm changes no rate).
    pub fn new() -> Self {
        Self {
            prior: GyroPrior::new(ImuConfig::new()),
            buf: [ImuSample::default(); CAPACITY],
            n: 0,
            used: Prior::First,
            residual: None,
        }
    }

    /// Before frame `i` (of the embedded ones), whose sweep ends at `end`.
    pub fn before<S: Storage>(
        &mut self,
        odom: &mut Odometry<Scalar, Codec, S>,
        i: usize,
        end: f64,
    ) {
        let all: &[f64] = bytemuck::cast_slice(&BYTES.0);
        let (first, count) = frames::IMU.get(i).copied().unwrap_or((0, 0));
        self.n = 0;
        for (slot, s) in self
            .buf
            .iter_mut()
            .zip(all.chunks_exact(7).skip(first).take(count))
        {
            *slot = ImuSample {
                time: s[0],
                gyro: [s[1], s[2], s[3]].map(Scalar::of),
                accel: [s[4], s[5], s[6]].map(Scalar::of),
            };
            self.n += 1;
        }
        self.used = self.prior.before_frame(odom, &self.buf[..self.n], end);
    }

    /// After the frame: learns the bias.
    pub fn after<S: Storage>(&mut self, odom: &Odometry<Scalar, Codec, S>) {
        self.residual = self.prior.after_frame(odom);
    }

    /// The `imu` line of frame `i`, compared with the host twin's.
    pub fn print(&self, i: usize) {
        let b = self.prior.bias();
        out!(
            "imu {} prior={} samples={} bias={:e},{:e},{:e} residual={:e}",
            i,
            self.used.name(),
            self.n,
            b[0],
            b[1],
            b[2],
            self.residual.unwrap_or(Scalar::of(f64::NAN))
        );
    }
}
