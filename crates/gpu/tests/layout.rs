//! The GPU structs agree with their WGSL mirrors: a kernel writes every field from its
//! index (f32 fields as the index, u32 fields as 100 + index) and the bytes read back are
//! the Rust structs with those values, field for field (GPU.md §5.1).

use crate::common;

use gpu::layout::{GpuBvhNode, GpuItemBox, GpuObject, GpuPerturbation, GpuQuadric, LAYOUT_WGSL};
use gpu::{GpuOptions, Kernel};

fn run(body: &str, ty: &str, words: usize) -> Option<Vec<u32>> {
    let g = common::gpu(GpuOptions::default())?;
    let src = format!(
        "{LAYOUT_WGSL}
@group(0) @binding(0) var<storage, read_write> out: array<{ty}>;
@compute @workgroup_size(1)
fn fill() {{
    var v: {ty};
    {body}
    out[0] = v;
    out[1] = v;
}}"
    );
    let k = Kernel::new(&g, &src, "fill", 0).unwrap();
    Some(k.run(&g, &[], 2 * words, [1, 1, 1]).unwrap())
}

#[test]
fn quadric_and_perturbation_layouts() {
    let Some(out) = run(
        "for (var i = 0u; i < 10u; i++) { v.c[i] = f32(i); } v.pad[0] = 10.0; v.pad[1] = 11.0;",
        "GpuQuadric",
        12,
    ) else {
        return;
    };
    let q: &[GpuQuadric] = bytemuck::cast_slice(&out);
    let want = GpuQuadric {
        c: std::array::from_fn(|i| i as f32),
        pad: [10.0, 11.0],
    };
    assert_eq!(q, &[want, want]);
    let out = run(
        "for (var i = 0u; i < 10u; i++) { v.q[i] = f32(i); } v.f = 10.0; v.pad = 11.0;",
        "GpuPerturbation",
        12,
    )
    .unwrap();
    let p: &[GpuPerturbation] = bytemuck::cast_slice(&out);
    let want = GpuPerturbation {
        q: std::array::from_fn(|i| i as f32),
        f: 10.0,
        pad: 11.0,
    };
    assert_eq!(p, &[want, want]);
}

#[test]
fn bvh_node_layout() {
    let Some(out) = run(
        "v.lo_x = 0.0; v.lo_y = 1.0; v.lo_z = 2.0; v.offset = 103u; \
         v.hi_x = 4.0; v.hi_y = 5.0; v.hi_z = 6.0; v.count_axis = 107u;",
        "GpuBvhNode",
        8,
    ) else {
        return;
    };
    let n: &[GpuBvhNode] = bytemuck::cast_slice(&out);
    let want = GpuBvhNode {
        lo: [0.0, 1.0, 2.0],
        offset: 103,
        hi: [4.0, 5.0, 6.0],
        count_axis: 107,
    };
    assert_eq!(n, &[want, want]);
}

#[test]
fn item_box_layout() {
    let Some(out) = run(
        "v.lo_x = 0.0; v.lo_y = 1.0; v.lo_z = 2.0; v.item = 103u; \
         v.hi_x = 4.0; v.hi_y = 5.0; v.hi_z = 6.0; v.pad = 107u;",
        "GpuItemBox",
        8,
    ) else {
        return;
    };
    let b: &[GpuItemBox] = bytemuck::cast_slice(&out);
    let want = GpuItemBox {
        lo: [0.0, 1.0, 2.0],
        item: 103,
        hi: [4.0, 5.0, 6.0],
        pad: 107,
    };
    assert_eq!(b, &[want, want]);
}

#[test]
fn object_layout() {
    let Some(out) = run(
        "v.kind = 100u; v.material = 101u; v.flags = 102u; v.unbounded = 103u; \
         v.lo_x = 4.0; v.lo_y = 5.0; v.lo_z = 6.0; v.first_node = 107u; \
         v.hi_x = 8.0; v.hi_y = 9.0; v.hi_z = 10.0; v.node_count = 111u; \
         v.first_item = 112u; v.item_count = 113u; v.first_op = 114u; v.op_count = 115u;",
        "GpuObject",
        16,
    ) else {
        return;
    };
    let o: &[GpuObject] = bytemuck::cast_slice(&out);
    let want = GpuObject {
        kind: 100,
        material: 101,
        flags: 102,
        unbounded: 103,
        lo: [4.0, 5.0, 6.0],
        first_node: 107,
        hi: [8.0, 9.0, 10.0],
        node_count: 111,
        first_item: 112,
        item_count: 113,
        first_op: 114,
        op_count: 115,
    };
    assert_eq!(o, &[want, want]);
}
