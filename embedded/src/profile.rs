//! What this build is: its scalar, map point codec and capacities (chosen by features), the
//! arena they need, the exit statuses and the instruction-count marker every workload shares.

use kiss_odom_core::Capacities;

/// Scalar of this build (`f64` feature; `f32` otherwise).
#[cfg(feature = "f64")]
pub type Scalar = f64;
/// Scalar of this build (`f64` feature; `f32` otherwise).
#[cfg(not(feature = "f64"))]
pub type Scalar = f32;

/// Map point codec of this build (`exact` feature; `Quantized` otherwise).
#[cfg(feature = "exact")]
pub type Codec = kiss_odom_core::Exact;
/// Map point codec of this build (`exact` feature; `Quantized` otherwise).
#[cfg(not(feature = "exact"))]
pub type Codec = kiss_odom_core::Quantized;

/// Capacities of this build (`full` feature: full scale; `tiny`: a 16-beam sensor in 512 KiB,
/// `TINY_ACCURATE` with `accurate`; microcontroller scale otherwise).
/// The `robust` and `accurate` features add room for point-to-plane terms.
pub const CAPS: Capacities = Capacities {
    plane_terms: cfg!(any(feature = "robust", feature = "accurate")),
    ..SIZES
};
#[cfg(feature = "full")]
const SIZES: Capacities = Capacities::FULL_SCALE;
#[cfg(all(
    any(feature = "tiny", feature = "packets", feature = "net"),
    not(feature = "accurate")
))]
const SIZES: Capacities = Capacities::TINY;
#[cfg(all(
    any(feature = "tiny", feature = "packets", feature = "net"),
    feature = "accurate"
))]
const SIZES: Capacities = Capacities::TINY_ACCURATE;
#[cfg(not(any(
    feature = "full",
    feature = "tiny",
    feature = "packets",
    feature = "net"
)))]
const SIZES: Capacities = Capacities::SMALL;

/// Arena length in `u64` words, computed at compile time so the arena can be a `static`.
pub const ARENA_WORDS: usize = CAPS.arena_words::<Scalar, Codec>();

pub const SCALAR_NAME: &str = if core::mem::size_of::<Scalar>() == 8 {
    "f64"
} else {
    "f32"
};
pub const CODEC_NAME: &str = if cfg!(feature = "exact") {
    "exact"
} else {
    "quantized"
};
pub const CAPS_NAME: &str = if cfg!(feature = "full") {
    "full_scale"
} else if cfg!(any(feature = "tiny", feature = "packets", feature = "net")) {
    if cfg!(feature = "accurate") {
        "tiny_accurate"
    } else {
        "tiny"
    }
} else {
    "small"
};

/// Called right before and right after each `register_frame`: the Cortex-M instruction-count
/// plugin prints its running count whenever this function's first instruction executes.
#[no_mangle]
#[inline(never)]
pub extern "C" fn kiss_frame_mark() {
    core::hint::black_box(());
}

/// Exit status of a frame that returned an error.
#[cfg_attr(feature = "net", allow(dead_code))]
pub const EXIT_FRAME_ERROR: i32 = 2;
/// Exit status when the odometry could not be built.
pub const EXIT_CONFIG_ERROR: i32 = 3;
