//! Error of an image against the reference, in f64 over all pixels and channels,
//! unclamped (negative pixel values are legitimate for optimal MIS, RESEARCH.md §2).

use super::{Image, ImageError};

/// The ε of relMSE = mean over pixels and channels of (x − ref)² / (ref² + ε): it keeps
/// near-black pixels from dominating the relative error.
pub const REL_EPSILON: f64 = 1e-2;

/// The share of pixels, the worst by squared error, that the trimmed MSE leaves out:
/// image RMSE is often carried by a few glossy highlights (docs/results.md).
pub const TRIM_FRACTION: f64 = 1e-3;

/// The error of one image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Mean squared error.
    pub mse: f64,
    /// Mean relative squared error, with [`REL_EPSILON`].
    pub relmse: f64,
    /// MSE without the worst [`TRIM_FRACTION`] of pixels (⌊fraction × pixels⌋ of them).
    pub trimmed_mse: f64,
    /// How many channel values of the image are NaN or infinite (they make MSE non-finite).
    pub nonfinite: u64,
}

impl Image {
    /// An error unless the image has at least one pixel and `width × height` of them.
    pub fn validate(&self) -> Result<(), ImageError> {
        let n = self.width as u64 * self.height as u64;
        if n == 0 {
            return Err(ImageError::Empty {
                width: self.width,
                height: self.height,
            });
        }
        if self.rgb.len() as u64 != n {
            return Err(ImageError::Values {
                width: self.width,
                height: self.height,
                values: self.rgb.len(),
            });
        }
        Ok(())
    }

    /// The image with every value rounded to f32, as an EXR file stores it: the
    /// reference is always used in this form, so that a reference rendered now and one
    /// reloaded on resume give the same numbers.
    pub fn rounded_to_f32(&self) -> Image {
        let rgb = self
            .rgb
            .iter()
            .map(|p| p.map(|v| v as f32 as f64))
            .collect();
        Image {
            width: self.width,
            height: self.height,
            rgb,
        }
    }

    /// A 64-bit FNV-1a hash of the size and the f32 bits of every value, as hex: tells
    /// on resume whether the reference is still the one the results were measured against.
    pub fn fingerprint(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        eat(&self.width.to_le_bytes());
        eat(&self.height.to_le_bytes());
        for p in &self.rgb {
            for v in p {
                eat(&(*v as f32).to_bits().to_le_bytes());
            }
        }
        format!("{h:016x}")
    }
}

/// The metrics of `img` against `reference` and the per-pixel squared error
/// (x − ref)² of each channel; an error if the sizes differ.
pub fn measure(img: &Image, reference: &Image) -> Result<(Metrics, Vec<[f64; 3]>), ImageError> {
    img.validate()?;
    reference.validate()?;
    if (img.width, img.height) != (reference.width, reference.height) {
        return Err(ImageError::Sizes {
            image: (img.width, img.height),
            what: "reference",
            other: (reference.width, reference.height),
        });
    }
    let mut sq = Vec::with_capacity(img.rgb.len());
    let (mut sum, mut rel, mut nonfinite) = (0.0, 0.0, 0u64);
    for (x, r) in img.rgb.iter().zip(&reference.rgb) {
        let mut e = [0.0; 3];
        for c in 0..3 {
            let d = x[c] - r[c];
            e[c] = d * d;
            sum += e[c];
            rel += e[c] / (r[c] * r[c] + REL_EPSILON);
            nonfinite += u64::from(!x[c].is_finite());
        }
        sq.push(e);
    }
    let n = 3.0 * img.rgb.len() as f64;
    let m = Metrics {
        mse: sum / n,
        relmse: rel / n,
        trimmed_mse: trimmed_mean(&sq),
        nonfinite,
    };
    Ok((m, sq))
}

/// The mean of per-pixel squared errors (over channels) without the worst
/// [`TRIM_FRACTION`] of pixels; NaN values count as the worst.
pub fn trimmed_mean(sq: &[[f64; 3]]) -> f64 {
    let mut px: Vec<f64> = sq.iter().map(|e| (e[0] + e[1] + e[2]) / 3.0).collect();
    let drop = (TRIM_FRACTION * px.len() as f64) as usize;
    let keep = px.len() - drop;
    if drop > 0 {
        px.select_nth_unstable_by(keep - 1, |a, b| a.total_cmp(b));
    }
    px[..keep].iter().sum::<f64>() / keep as f64
}
