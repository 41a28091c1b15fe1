//! Opening the test GPU: lavapipe on machines without one.

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
