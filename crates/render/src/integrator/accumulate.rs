//! The CPU's side of a render shaded by another back end: the per-pixel bookkeeping of
//! [`state::Tally`] (how samples shaded elsewhere enter the records) together with what
//! only the CPU has, the trained light selection and the samples the other back end
//! hands back.

use super::{Integrator, RayCounts, RenderOptions};
use crate::bsdf::CoatTable;
use crate::color::luminance;
use crate::light::{AreaLight, LightTree, TrainedSelection};
use crate::scene::Scene;
use state::{CoatAlbedo, Host, LightBounds, LightTreeTable, OptionsError, Tally};

/// The `direct` and `path` integrators' bookkeeping for samples shaded elsewhere: a
/// [`Tally`] (through `Deref`) and the CPU integrator behind it.
#[derive(Clone, Debug)]
pub struct Accumulator {
    it: Integrator,
}

impl std::ops::Deref for Accumulator {
    type Target = Tally;
    fn deref(&self) -> &Tally {
        &self.it
    }
}

impl Accumulator {
    /// The accumulator of a render of `scene` with `options` (the options are validated
    /// and checked against the scene as a CPU render would).
    pub fn new(scene: &Scene, options: &RenderOptions) -> Result<Self, OptionsError> {
        let mut it = Integrator::new(options)?;
        it.prepare(scene)?;
        Ok(Self { it })
    }

    /// The light selection trained for this render (`light-trained`), if it has one.
    pub fn trained(&self) -> Option<&TrainedSelection> {
        self.it.trained.as_deref()
    }

    /// Renders sample `index` of pixel (x, y) on the CPU into `rec`, for the samples an
    /// external back end could not finish (a ray past a fixed capacity).
    pub fn cpu_sample(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        index: u32,
        rec: &mut [f64],
        rays: &mut RayCounts,
    ) {
        self.it.sample(scene, x, y, index, rec, rays);
    }
}

impl From<&AreaLight> for LightBounds {
    /// What the spatial selection's importance reads of `l`: its
    /// [`AreaLight::importance_bounds`] and the luminance of its power.
    fn from(l: &AreaLight) -> Self {
        let b = l.importance_bounds();
        LightBounds {
            center: b.center,
            radius: b.radius,
            axis: b.axis,
            cos_o: b.cos_o,
            two_sided: b.two_sided,
            power: luminance(l.power()),
        }
    }
}

/// The CPU renderer of `scene` with one set of options, as the GPU back end takes it
/// ([`state::Host`]): the [`Accumulator`], the tables computed by the CPU's own code, and
/// the samples the GPU hands back.
pub struct CpuHost<'a> {
    scene: &'a Scene,
    acc: Accumulator,
}

impl<'a> CpuHost<'a> {
    /// The host of a render of `scene` with `options` (validated, checked against the
    /// scene and trained as a CPU render would be).
    pub fn new(scene: &'a Scene, options: &RenderOptions) -> Result<Self, OptionsError> {
        Ok(Self {
            scene,
            acc: Accumulator::new(scene, options)?,
        })
    }
}

impl Host for CpuHost<'_> {
    fn tally(&self) -> &Tally {
        &self.acc
    }

    fn trained(&self) -> Option<&TrainedSelection> {
        self.acc.trained()
    }

    fn coat_albedo(&self, eta: f64, alpha: f64, mu: &[f64]) -> CoatAlbedo {
        let coat = CoatTable::new(eta, alpha);
        CoatAlbedo {
            albedo: mu.iter().map(|&m| coat.albedo(m)).collect(),
            r_int: coat.r_int,
        }
    }

    fn light_bounds(&self, light: &scene::Light) -> Option<LightBounds> {
        AreaLight::from_data(light).map(|l| LightBounds::from(&l))
    }

    fn light_tree(&self) -> Option<LightTreeTable> {
        self.scene.lights.tree().map(LightTree::table)
    }

    fn cpu_sample(&self, x: u32, y: u32, index: u32, rec: &mut [f64], rays: &mut RayCounts) {
        self.acc.cpu_sample(self.scene, x, y, index, rec, rays);
    }
}
