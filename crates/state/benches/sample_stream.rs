//! Time to read a sample's random numbers with four Philox blocks kept per evaluation
//! (SSE2) and with eight (AVX2 lanes, where the CPU has them), for three reading
//! patterns of `state::dims`: dimensions 0–13 (a `direct` sample with two techniques,
//! the table scene), 0–16 (three techniques, many-lights: one dimension past four
//! blocks) and 0–71 (a `path` sample of four vertices).
//!
//! `cargo bench -p state --bench sample_stream [-- SAMPLES ROUNDS]` (default 2 000 000
//! samples, 3 rounds); prints ns a sample for each pattern, window and round, the
//! windows alternating.

use state::sampler::Sampler;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let args: Vec<u64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let samples = args.first().copied().unwrap_or(2_000_000) as u32;
    let rounds = args.get(1).copied().unwrap_or(3) as u32;
    let s = Sampler::new(99);
    let eight = s.stream_keeping(0, 0, 0, 8) != s.stream_keeping(0, 0, 0, 4);
    println!("eight blocks in AVX2 lanes on this CPU: {eight}");
    println!("| dimensions | round | 4 blocks (ns/sample) | 8 blocks (ns/sample) |");
    println!("| --- | --- | ---: | ---: |");
    for dims in [14u32, 17, 72] {
        for round in 0..rounds {
            let time = |blocks: u32| {
                let t0 = Instant::now();
                let mut acc = 0.0;
                for i in 0..samples {
                    let t = s.stream_keeping(i & 1023, i >> 10, round, blocks);
                    for d in 0..dims {
                        acc += t.get(d);
                    }
                }
                black_box(acc);
                t0.elapsed().as_nanos() as f64 / f64::from(samples)
            };
            let (four, eight) = (time(4), time(8));
            println!("| 0–{} | {round} | {four:.1} | {eight:.1} |", dims - 1);
        }
    }
}
