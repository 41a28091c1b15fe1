//! What a render reports at its end, from either back end: time, samples, rays and
//! their rates (MSamples/s, MRays/s).

use crate::counts::RayCounts;
use scene::IntegratorKind;
use std::fmt;
use std::time::Duration;

/// What a render did and how fast.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderStats {
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Wall time of the render (passes and film assembly).
    pub wall: Duration,
    /// Samples (pixel iterations) rendered.
    pub samples: u64,
    /// Samples asked for (pixels × spp).
    pub samples_requested: u64,
    /// Rays traced, by kind.
    pub rays: RayCounts,
    /// Whether the stop flag ended the render early.
    pub stopped: bool,
    /// Worker threads; 0 where the GPU rendered.
    pub threads: usize,
}

impl RenderStats {
    fn per_second(&self, n: u64) -> f64 {
        let s = self.wall.as_secs_f64();
        if s > 0.0 {
            n as f64 / s / 1e6
        } else {
            0.0
        }
    }
    /// Millions of samples per second.
    pub fn msamples_per_s(&self) -> f64 {
        self.per_second(self.samples)
    }
    /// Millions of rays per second, all kinds.
    pub fn mrays_per_s(&self) -> f64 {
        self.per_second(self.rays.total())
    }
    /// Millions of (camera, secondary, shadow) rays per second.
    pub fn mrays_per_s_by_kind(&self) -> (f64, f64, f64) {
        (
            self.per_second(self.rays.camera),
            self.per_second(self.rays.secondary),
            self.per_second(self.rays.shadow),
        )
    }
}

impl RenderStats {
    /// Records the statistics in `img`'s EXR attributes: the line this type displays,
    /// and the wall time, samples and rays as numbers.
    pub fn describe(&self, img: &mut crate::Image) {
        let p = scene::ATTRIBUTE_PREFIX;
        img.set_attribute(&format!("{p}statistics"), self.to_string());
        img.set_attribute(
            &format!("{p}time_s"),
            format!("{:.6}", self.wall.as_secs_f64()),
        );
        img.set_attribute(&format!("{p}samples_rendered"), self.samples.to_string());
        img.set_attribute(&format!("{p}rays"), self.rays.total().to_string());
        img.set_attribute(&format!("{p}threads"), self.threads.to_string());
    }
}

impl fmt::Display for RenderStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (c, s, sh) = self.mrays_per_s_by_kind();
        let on = match self.threads {
            0 => "the GPU".to_string(),
            1 => "1 thread".to_string(),
            n => format!("{n} threads"),
        };
        write!(
            f,
            "{}: {:.3} s on {}, {} samples{} ({:.3} MSamples/s); rays: {:.3} MRays/s \
             (camera {} = {:.3} M/s, secondary {} = {:.3} M/s, shadow {} = {:.3} M/s)",
            self.integrator,
            self.wall.as_secs_f64(),
            on,
            self.samples,
            if self.stopped { " (stopped)" } else { "" },
            self.msamples_per_s(),
            self.mrays_per_s(),
            self.rays.camera,
            c,
            self.rays.secondary,
            s,
            self.rays.shadow,
            sh
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line says where the render ran: on the GPU (no worker threads), on 1 thread,
    /// on n threads.
    #[test]
    fn the_line_names_the_back_end_and_threads() {
        let stats = |threads| RenderStats {
            integrator: IntegratorKind::Direct,
            wall: Duration::from_secs(2),
            samples: 4_000_000,
            samples_requested: 4_000_000,
            rays: RayCounts::default(),
            stopped: false,
            threads,
        };
        let line = |t| stats(t).to_string();
        assert!(
            line(0).starts_with("direct: 2.000 s on the GPU, 4000000 samples (2.000 MSamples/s)"),
            "{}",
            line(0)
        );
        assert!(line(1).contains(" s on 1 thread, "), "{}", line(1));
        assert!(line(8).contains(" s on 8 threads, "), "{}", line(8));
    }
}
