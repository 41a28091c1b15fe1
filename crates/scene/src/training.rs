//! How the trained light selection (`light-trained`) is trained: the spatial grid its
//! pmfs live in, the uniform floor mixed into them, and the training rays per pixel
//! (scene keys `trained_grid`, `trained_floor`, `trained_spp` of `[render]`). The pass
//! itself is the renderer's (`render::integrator`, `integrator/train.rs`).

/// The training of `light-trained`. The defaults are the values the technique was
/// introduced with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Training {
    /// Cells per axis of the grid over the first-hit points (1: one pmf for the whole
    /// scene, the measured contribution of each light summed over every shading point).
    pub grid: u32,
    /// The uniform share ε of every cell's pmf, `P(k) = (1 − ε)·w_k/Σw + ε/L`, in (0, 1]:
    /// above 0 so that no light gets probability 0 (which would bias an estimator that
    /// relies on this technique alone); 1 is uniform selection.
    pub floor: f64,
    /// Camera rays per pixel of the training pass (each shades its first hit once).
    pub spp: u32,
}

/// The largest grid: `grid³ × lights` probabilities are kept (64³ × 64 lights is 128 MiB).
pub const MAX_TRAINED_GRID: u32 = 64;

impl Default for Training {
    /// An 8³ grid, floor 0.1, 4 training rays per pixel.
    fn default() -> Self {
        Self {
            grid: 8,
            floor: 0.1,
            spp: 4,
        }
    }
}

impl Training {
    /// Checks each value; an error names the offending key (`trained_grid`,
    /// `trained_floor` or `trained_spp`) and says what is allowed.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if !(1..=MAX_TRAINED_GRID).contains(&self.grid) {
            return Err((
                "trained_grid",
                format!(
                    "trained_grid {} is not in 1..={MAX_TRAINED_GRID} (cells per axis of the \
                     training grid)",
                    self.grid
                ),
            ));
        }
        if !(self.floor > 0.0 && self.floor <= 1.0) {
            return Err((
                "trained_floor",
                format!(
                    "trained_floor {} is not in (0, 1]: the uniform share keeps every light's \
                     probability above 0",
                    self.floor
                ),
            ));
        }
        if self.spp == 0 {
            return Err((
                "trained_spp",
                "trained_spp must be at least 1 (training rays per pixel)".into(),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_validates_each_value() {
        assert!(Training::default().validate().is_ok());
        let d = Training::default();
        let key = |t: Training| t.validate().unwrap_err().0;
        assert_eq!(key(Training { grid: 0, ..d }), "trained_grid");
        assert_eq!(key(Training { grid: 65, ..d }), "trained_grid");
        assert!(Training { grid: 1, ..d }.validate().is_ok());
        for f in [0.0, -0.1, 1.5, f64::NAN] {
            assert_eq!(key(Training { floor: f, ..d }), "trained_floor");
        }
        assert!(Training { floor: 1.0, ..d }.validate().is_ok());
        assert_eq!(key(Training { spp: 0, ..d }), "trained_spp");
    }
}
