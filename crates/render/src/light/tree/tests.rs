use super::*;
use crate::testutil::chi2_pvalue;

/// SplitMix64 (Steele et al. 2014): the tests' uniform numbers, seeded.
struct Mix(u64);

impl Mix {
    fn gen(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn gen_range(&mut self, r: std::ops::Range<f64>) -> f64 {
        r.start + (r.end - r.start) * self.gen()
    }
}

/// `count` lights: spheres (a full cone), one- and two-sided planar lights, over a box
/// of side 20; a few with no power.
fn lights(count: usize, seed: u64) -> Vec<(ImportanceBounds, f64)> {
    let mut rng = Mix(seed);
    (0..count)
        .map(|k| {
            let center = DVec3::new(
                rng.gen_range(-10.0..10.0),
                rng.gen_range(-10.0..10.0),
                rng.gen_range(-10.0..10.0),
            );
            let axis = DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
            .normalize();
            let sphere = k % 3 == 0;
            let bounds = ImportanceBounds {
                center,
                radius: rng.gen_range(0.01..0.5),
                axis: if sphere { DVec3::Z } else { axis },
                cos_o: if sphere { -1.0 } else { 1.0 },
                two_sided: k % 3 == 2,
            };
            let phi = if k % 17 == 5 {
                0.0
            } else {
                rng.gen_range(0.1..100.0)
            };
            (bounds, phi)
        })
        .collect()
}

/// Shading points with normals, inside and around the lights' box.
fn points(count: usize, seed: u64) -> Vec<(DVec3, DVec3)> {
    let mut rng = Mix(seed);
    let mut v = || {
        DVec3::new(
            rng.gen_range(-12.0..12.0),
            rng.gen_range(-12.0..12.0),
            rng.gen_range(-12.0..12.0),
        )
    };
    (0..count).map(|_| (v(), v().normalize())).collect()
}

/// A draw reports the pmf of the light it drew, bit for bit; every light that can shine
/// on the point has a positive pmf (the nodes' bounds hold their lights', so no light
/// is lost to a node that rules it out) and every other a pmf of 0; the pmfs sum to at
/// most 1, to 1 where every light can shine. The rest is the mass of subtrees whose
/// bounds admit the point but whose lights cannot shine on it: draws there fail, as a
/// technique's draws may (MIS counts them as failed draws).
#[test]
fn draws_report_their_pmf_and_pmfs_sum_to_one() {
    let mut rng = Mix(3);
    let configs = [(1, 200), (2, 200), (10, 200), (10_000, 6)];
    for ((count, queries), spheres) in configs.into_iter().flat_map(|c| [(c, false), (c, true)]) {
        let mut ls = lights(count, count as u64);
        if spheres {
            // Every light shines everywhere: the pmfs sum to 1.
            for (b, phi) in &mut ls {
                (b.axis, b.cos_o, *phi) = (DVec3::Z, -1.0, phi.max(1.0));
            }
        }
        let tree = LightTree::new(&ls).unwrap();
        for (p, n) in points(queries, 7) {
            for _ in 0..50 {
                let u = rng.gen();
                if let Some((k, pmf)) = tree.sample(p, n, u) {
                    assert_eq!(pmf.to_bits(), tree.pmf(p, n, k).to_bits(), "{count} lights");
                    assert!(pmf > 0.0);
                }
            }
            let pmfs: Vec<f64> = (0..count).map(|k| tree.pmf(p, n, k)).collect();
            let sum: f64 = pmfs.iter().sum();
            let shining = ls
                .iter()
                .filter(|(b, phi)| importance_of(b, *phi, p, n) > 0.0)
                .count();
            assert!(sum <= 1.0 + 1e-9, "{count} lights: Σ pmf = {sum}");
            if shining == count {
                assert!((sum - 1.0).abs() < 1e-9, "{count} lights: Σ pmf = {sum}");
            }
            if shining == 0 {
                assert_eq!(sum, 0.0);
            }
            for (k, (b, phi)) in ls.iter().enumerate() {
                if importance_of(b, *phi, p, n) > 0.0 {
                    assert!(pmfs[k] > 0.0, "{count} lights: light {k} lost at {p}, {n}");
                } else {
                    assert_eq!(pmfs[k], 0.0, "{count} lights: light {k}");
                }
            }
        }
    }
}

/// Each light's share of N stratified draws is N·pmf within one draw on either side (its
/// draws are one interval of u of length pmf), on 1, 10 and 10 000 lights.
#[test]
fn stratified_draws_follow_the_pmf() {
    for count in [1, 10, 10_000] {
        let ls = lights(count, 11 + count as u64);
        let tree = LightTree::new(&ls).unwrap();
        for (p, n) in points(3, 5) {
            let draws = 200_000;
            let mut hits = vec![0u32; count];
            for i in 0..draws {
                if let Some((k, _)) = tree.sample(p, n, (i as f64 + 0.5) / draws as f64) {
                    hits[k] += 1;
                }
            }
            for (k, &h) in hits.iter().enumerate() {
                let want = tree.pmf(p, n, k) * draws as f64;
                assert!(
                    (f64::from(h) - want).abs() <= 2.0,
                    "{count} lights: light {k} drawn {h} times, pmf says {want}"
                );
            }
        }
    }
}

/// Random draws against the pmf by Pearson's chi-square on 10 lights (fixed seed,
/// rejected below p = 0.001).
#[test]
fn random_draws_pass_chi_square() {
    let ls = lights(10, 21);
    let tree = LightTree::new(&ls).unwrap();
    let mut rng = Mix(99);
    for (p, n) in points(5, 8) {
        let draws = 100_000;
        let mut hits = [0u32; 10];
        for _ in 0..draws {
            if let Some((k, _)) = tree.sample(p, n, rng.gen()) {
                hits[k] += 1;
            }
        }
        let (mut chi2, mut cells) = (0.0, 0);
        for (k, &h) in hits.iter().enumerate() {
            let e = tree.pmf(p, n, k) * draws as f64;
            if e > 0.0 {
                chi2 += (f64::from(h) - e).powi(2) / e;
                cells += 1;
            } else {
                assert_eq!(h, 0, "light {k} drawn with pmf 0");
            }
        }
        if cells > 1 {
            let pv = chi2_pvalue(chi2, cells - 1);
            assert!(
                pv > 0.001,
                "χ² = {chi2} over {cells} lights at {p}: p = {pv}"
            );
        }
    }
}

/// The unions hold their parts: a sphere around both spheres, a cone around both cones.
#[test]
fn unions_enclose_their_parts() {
    let mut rng = Mix(4);
    let mut unit = || {
        DVec3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        )
        .normalize()
    };
    for _ in 0..2000 {
        let (ca, cb) = (unit() * 3.0, unit() * 2.0);
        let (ra, rb) = (unit().x.abs() + 0.1, unit().y.abs() + 0.2);
        let (c, r) = sphere_union(ca, ra, cb, rb);
        assert!((ca - c).length() + ra <= r * (1.0 + 1e-12));
        assert!((cb - c).length() + rb <= r * (1.0 + 1e-12));
        let (wa, wb) = (unit(), unit());
        let (cos_a, cos_b) = (unit().x, unit().y);
        let (w, cos_o) = cone_union(wa, cos_a, wb, cos_b);
        let theta = cos_o.clamp(-1.0, 1.0).acos();
        for (wi, ci) in [(wa, cos_a), (wb, cos_b)] {
            let needed = (angle_between(w, wi) + ci.acos()).min(std::f64::consts::PI);
            assert!(needed <= theta + 1e-9, "{w} {cos_o}");
        }
    }
}

/// [`LightTree::pmf`] without the memo: the descent evaluated in full.
fn pmf_in_full(tree: &LightTree, p: DVec3, n: DVec3, k: usize) -> f64 {
    let (trail, depth) = tree.trails[k];
    let (mut i, mut pmf) = (0, 1.0);
    for d in 0..depth {
        let Some([pa, pb]) = tree.split(i, p, n) else {
            return 0.0;
        };
        if trail >> d & 1 == 0 {
            (pmf, i) = (pmf * pa, i + 1);
        } else {
            (pmf, i) = (pmf * pb, tree.nodes[i].index as usize);
        }
    }
    if tree.importance(i, p, n) > 0.0 {
        pmf
    } else {
        0.0
    }
}

/// The memo of node splits changes no value: pmfs and draws interleaved across two
/// trees, several points and many lights equal the descents evaluated in full, bit for
/// bit.
#[test]
fn the_memo_changes_no_value() {
    let trees = [
        LightTree::new(&lights(1000, 1)).unwrap(),
        LightTree::new(&lights(300, 2)).unwrap(),
    ];
    let pts = points(4, 9);
    let mut rng = Mix(12);
    for step in 0..20_000 {
        // Runs of a few steps on one tree and point (the memo's entries reused, over paths
        // sharing nodes or not, slots shared by nodes 256 apart), then another.
        let tree = &trees[(step / 7) % 2];
        let (p, n) = pts[(step / 3) % pts.len()];
        let count = tree.trails.len();
        if step % 5 == 0 {
            if let Some((k, pmf)) = tree.sample(p, n, rng.gen()) {
                assert_eq!(pmf.to_bits(), pmf_in_full(tree, p, n, k).to_bits());
            }
        } else {
            let k = ((rng.gen() * count as f64) as usize).min(count - 1);
            let want = pmf_in_full(tree, p, n, k);
            assert_eq!(tree.pmf(p, n, k).to_bits(), want.to_bits(), "step {step}");
        }
    }
}
