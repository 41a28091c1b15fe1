//! The device: adapter choice, forced-off features, and errors instead of panics.

use crate::common;

use gpu::{GpuError, GpuOptions, Kernel};

/// Forcing features off is honoured, and the device reports what it uses.
#[test]
fn features_can_be_forced_off() {
    let off = GpuOptions::default()
        .with("f64=off, int64=0,subgroups=false,sums=off,checked")
        .unwrap();
    assert_eq!(
        off,
        GpuOptions {
            f64: false,
            int64: false,
            subgroups: false,
            sums: false,
            checked: true,
            adapter: None,
        }
    );
    assert_eq!(
        GpuOptions::default().with("adapter=2").unwrap().adapter,
        Some(2)
    );
    assert!(matches!(
        GpuOptions::default().with("adapter=gpu"),
        Err(gpu::GpuOptionError::Value { .. })
    ));
    assert_eq!(
        GpuOptions::default().with("f32").unwrap_err(),
        gpu::GpuOptionError::Unknown("f32".into())
    );
    let e = GpuOptions::default().with("f64=maybe").unwrap_err();
    assert!(matches!(&e, gpu::GpuOptionError::Value { value, .. } if value == "maybe"));
    assert!(e.to_string().contains("maybe"), "{e}");
    let Some(g) = common::gpu(off) else { return };
    let i = g.info();
    assert!(
        !i.f64 && !i.int64 && !i.subgroups && !i.sums && i.checked,
        "{i}"
    );
    assert!(i.max_storage_binding >= 128 << 20, "{i}");
    assert!(!i.name.is_empty());
}

/// A shader that does not compile and a binding over the device's limit are errors
/// that say what is wrong.
#[test]
fn bad_shaders_and_limits_are_errors() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let e = Kernel::new(&g, "fn main( {", "main", 0)
        .err()
        .expect("a parse error");
    assert!(matches!(e, GpuError::Run(_)), "{e}");
    let too_big = g.info().max_storage_binding + 4;
    let e = g.check_binding(too_big).unwrap_err();
    assert!(
        e.to_string().contains("max_storage_buffer_binding_size"),
        "{e}"
    );
}

/// A kernel runs over inputs and its output is read back.
#[test]
fn a_kernel_adds_two_arrays() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let src = r#"
@group(0) @binding(0) var<storage, read> a: array<u32>;
@group(0) @binding(1) var<storage, read> b: array<u32>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn add(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < arrayLength(&out)) { out[id.x] = a[id.x] + b[id.x]; }
}
"#;
    let k = Kernel::new(&g, src, "add", 2).unwrap();
    let a: Vec<u32> = (0..1000).collect();
    let b: Vec<u32> = (0..1000).map(|i| 3 * i + 7).collect();
    let out = k.run(&g, &[&a, &b], 1000, [16, 1, 1]).unwrap();
    assert!(out.iter().enumerate().all(|(i, &v)| v == 4 * i as u32 + 7));
}
