//! Opening the test GPU (lavapipe on machines without one), and the tests' random
//! inputs.
#![allow(dead_code)] // each test binary uses its own part

use gpu::{Gpu, GpuOptions};

/// The GPU, or None (saying so) when there is none and `FREPRAY_REQUIRE_GPU` is not 1;
/// with it set, a missing adapter fails the test (GPU.md §11.1).
pub fn gpu(options: GpuOptions) -> Option<Gpu> {
    match Gpu::new(&options) {
        Ok(g) => {
            eprintln!("GPU: {}", g.info());
            Some(g)
        }
        Err(e) if std::env::var("FREPRAY_REQUIRE_GPU").as_deref() == Ok("1") => {
            panic!("FREPRAY_REQUIRE_GPU=1 but {e}")
        }
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

/// Whether the long comparisons run (`FREPRAY_LONG=1`, as `scripts/long-test.sh` sets):
/// every case of each image comparison. The test command runs one case per integrator
/// and estimator family.
pub fn long() -> bool {
    std::env::var("FREPRAY_LONG").as_deref() == Ok("1")
}

/// The cases to run: all when [`long`], else those `quick` marks.
pub fn cases<T>(all: Vec<(bool, T)>) -> Vec<T> {
    let long = long();
    all.into_iter()
        .filter(|(quick, _)| long || *quick)
        .map(|(_, c)| c)
        .collect()
}

/// A small deterministic generator for test inputs (SplitMix64, Steele et al. 2014);
/// each test adds the shapes of input it needs in an `impl Rng` of its own.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn bits(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1), 53 bits.
    pub fn next(&mut self) -> f64 {
        (self.bits() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}
