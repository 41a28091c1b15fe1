//! The solid pool: each object's solid in frep's flat form ([`frep::Flat`]: CSG nodes,
//! leaf table, pools of quadrics, perturbations, BVH nodes, tapes and bytecode), built
//! once when the scene is resolved, with transforms folded in.
//!
//! The renderer intersects these solids as they are, and a GPU uploads the same arrays;
//! two resolutions of the same scene compare equal, and `--dump-scene` writes the arrays
//! as JSON (infinite bounds as `null`; expression constants as their f64 bit patterns).

use crate::data::SolidId;
use frep::Solid;
use serde::{Serialize, Serializer};

/// The solids of a scene (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolidPool {
    solids: Vec<Solid>,
}

impl SolidPool {
    /// Adds a solid; returns its id.
    pub fn push(&mut self, solid: Solid) -> SolidId {
        self.solids.push(solid);
        SolidId(self.solids.len() as u32 - 1)
    }

    /// The solid of `id`.
    pub fn solid(&self, id: SolidId) -> &Solid {
        &self.solids[id.index()]
    }

    /// The bounds of `id`'s solid (possibly infinite for an unbounded solid).
    pub fn bounds(&self, id: SolidId) -> frep::Aabb {
        use frep::Surface;
        self.solids[id.index()].bounds()
    }

    /// Number of solids.
    pub fn len(&self) -> usize {
        self.solids.len()
    }

    /// Whether the pool is empty.
    pub fn is_empty(&self) -> bool {
        self.solids.is_empty()
    }
}

impl Serialize for SolidPool {
    /// A list of the solids' flat forms.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.solids.iter().map(Solid::flat))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frep::{Shape, Tree};

    #[test]
    fn equal_functions_have_equal_solids() {
        let ball = |r: f64| {
            let t = Tree::constant(r * r)
                - (Tree::x().square() + Tree::y().square() + Tree::z().square());
            Solid::build(&Shape::function(t)).unwrap()
        };
        assert_eq!(ball(1.0), ball(1.0));
        assert_ne!(ball(1.0), ball(2.0));
        let mut pool = SolidPool::default();
        let id = pool.push(ball(1.0));
        assert_eq!((id, pool.len()), (SolidId(0), 1));
        assert!((pool.bounds(id).hi.x - 1.0).abs() < 0.1);
        let json = serde_json::to_value(&pool).unwrap();
        assert_eq!(json[0]["leaves"].as_array().unwrap().len(), 1);
        assert!(json[0]["tapes"].as_array().unwrap().len() > 3);
        assert!(json[0]["bytecode"].is_array());
    }
}
