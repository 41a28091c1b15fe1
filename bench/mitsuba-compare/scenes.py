"""The comparison scenes as Mitsuba 3 dicts: each function is the twin of
scenes/NAME.toml and must describe the same geometry, materials, lights and camera.

Conventions bridged here (frepray → Mitsuba):
- `box(center, size)` → the `cube` mesh ([-1, 1]³) scaled by size/2, then moved.
- a rect light by `corner`, `edge_u`, `edge_v` → a `rectangle` ([-1, 1]², normal +z)
  whose local x, y, z go to edge_u/2, edge_v/2 and their unit cross product, so that it
  emits on the same side (both are one-sided).
- light shapes get a black BSDF: in Mitsuba a shape with an emitter otherwise reflects
  with the default 50 % diffuse BSDF, in frepray lights do not reflect.
- `fov` is vertical in frepray: `fov_axis = "y"`. Box pixel filter, independent sampler.
- rough conductors: Mitsuba's GGX uses the separable G2 = G1(ωi)·G1(ωo), frepray the
  height-correlated one (g2.py offers the latter to Mitsuba, as a diagnostic).
- colours are plain RGB (`rgb` variants, no spectral upsampling); conductor η, k are
  given per channel as in the TOML.
"""

import math


def _rgb(v):
    v = [v] * 3 if isinstance(v, (int, float)) else list(v)
    return {"type": "rgb", "value": v}


def _diffuse(rgb):
    return {"type": "diffuse", "reflectance": _rgb(rgb)}


# The conductor plugin: "roughconductor", or g2.py's "roughconductor_g2corr" (frepray's
# height-correlated G2) for compare.py --g2 correlated.
CONDUCTOR = "roughconductor"


def _conductor(eta, k, alpha):
    return {"type": CONDUCTOR, "distribution": "ggx", "alpha": alpha,
            "eta": _rgb(eta), "k": _rgb(k)}


_BLACK = {"type": "diffuse", "reflectance": _rgb(0.0)}


def _camera(mi, eye, target, fov, width, height, spp):
    return {
        "type": "perspective",
        "fov": fov,
        "fov_axis": "y",
        "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=target, up=[0, 0, 1]),
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp},
    }


def _box(mi, center, size, bsdf, rotate_z=0.0, translate=(0, 0, 0)):
    """frepray's `box(center, size)` turned by rotate_z degrees about the z axis through
    the origin, then translated (the order of the TOML's transform list)."""
    t = (mi.ScalarTransform4f().translate(list(translate))
         @ mi.ScalarTransform4f().rotate(axis=[0, 0, 1], angle=rotate_z)
         @ mi.ScalarTransform4f().translate(list(center))
         @ mi.ScalarTransform4f().scale([s / 2 for s in size]))
    return {"type": "cube", "to_world": t, "bsdf": bsdf}


def _sphere(center, radius, bsdf):
    return {"type": "sphere", "center": list(center), "radius": radius, "bsdf": bsdf}


def _sphere_light(center, radius, radiance):
    s = _sphere(center, radius, _BLACK)
    s["emitter"] = {"type": "area", "radiance": _rgb(radiance)}
    return s


def _rect_light(mi, corner, edge_u, edge_v, radiance):
    cross = [edge_u[1] * edge_v[2] - edge_u[2] * edge_v[1],
             edge_u[2] * edge_v[0] - edge_u[0] * edge_v[2],
             edge_u[0] * edge_v[1] - edge_u[1] * edge_v[0]]
    norm = math.sqrt(sum(c * c for c in cross))
    n = [c / norm for c in cross]
    c = [corner[i] + (edge_u[i] + edge_v[i]) / 2 for i in range(3)]
    m = [[edge_u[i] / 2, edge_v[i] / 2, n[i], c[i]] for i in range(3)] + [[0, 0, 0, 1]]
    return {"type": "rectangle", "to_world": mi.ScalarTransform4f(m), "bsdf": _BLACK,
            "emitter": {"type": "area", "radiance": _rgb(radiance)}}


def diffuse(mi, width, height, spp):
    return {
        "type": "scene",
        "camera": _camera(mi, [0, -5, 2.2], [0, 0, 0.6], 40, width, height, spp),
        "floor": _box(mi, [0, 0, -0.05], [8, 8, 0.1], _diffuse(0.7)),
        "ball": _sphere([-0.9, 0, 0.6], 0.6, _diffuse([0.7, 0.25, 0.15])),
        "block": _box(mi, [0.9, 0.3, 0.45], [0.9, 0.9, 0.9], _diffuse([0.15, 0.3, 0.7])),
        "rect": _rect_light(mi, [-1, 1, 3], [2, 0, 0], [0, -2, 0], 4),
        "bulb": _sphere_light([1.8, -1.2, 1.5], 0.2, [20, 16, 10]),
    }


def conductors(mi, width, height, spp):
    return {
        "type": "scene",
        "camera": _camera(mi, [0, -5, 1.8], [0, 0, 0.5], 40, width, height, spp),
        "floor": _box(mi, [0, 0, -0.05], [8, 8, 0.1], _diffuse(0.5)),
        "gold": _sphere([-1.3, 0, 0.5], 0.5,
                        _conductor([0.143, 0.374, 1.442], [3.983, 2.385, 1.603], 0.1)),
        "copper": _sphere([0, 0.3, 0.5], 0.5,
                          _conductor([0.200, 0.924, 1.102], [3.912, 2.452, 2.142], 0.3)),
        "aluminium": _sphere([1.3, 0, 0.5], 0.5,
                             _conductor([1.657, 0.880, 0.521], [9.224, 6.270, 4.837], 0.5)),
        "warm": _sphere_light([-2, -1.5, 2], 0.25, [30, 22, 14]),
        "cool": _sphere_light([2, -1, 1.2], 0.15, [12, 20, 40]),
        "rect": _rect_light(mi, [-1, 2, 1], [2, 0, 0], [0, 0.8, 0.8], 3),
    }


def room(mi, width, height, spp):
    white = _diffuse(0.73)
    return {
        "type": "scene",
        "camera": _camera(mi, [0, -3.9, 1], [0, 0, 1], 38, width, height, spp),
        "floor": _box(mi, [0, 0, -0.05], [2.2, 2.2, 0.1], white),
        "ceiling": _box(mi, [0, 0, 2.05], [2.2, 2.2, 0.1], white),
        "back": _box(mi, [0, 1.05, 1], [2.2, 0.1, 2.2], white),
        "left": _box(mi, [-1.05, 0, 1], [0.1, 2.2, 2.2], _diffuse([0.63, 0.065, 0.05])),
        "right": _box(mi, [1.05, 0, 1], [0.1, 2.2, 2.2], _diffuse([0.14, 0.45, 0.09])),
        "block": _box(mi, [0, 0, 0.6], [0.6, 0.6, 1.2],
                      _conductor([2.5, 2.4, 2.3], [3.2, 3.1, 3.0], 0.25),
                      rotate_z=18, translate=[-0.35, 0.35, 0]),
        "ball": _sphere([0.4, -0.3, 0.35], 0.35, white),
        "light": _rect_light(mi, [-0.25, 0.2, 1.99], [0.5, 0, 0], [0, -0.4, 0],
                             [15, 12.75, 9]),
    }


def _medium(albedo, mean_free_path, g=0.0):
    """frepray's `albedo` and `mean_free_path` as Mitsuba's `albedo` and σ_t = 1/mfp,
    given as `scale` × an RGB in [0, 1] (Mitsuba reads an RGB σ_t as a reflectance and
    refuses values above 1: mitsuba3 issue #1620)."""
    mfp = [mean_free_path] * 3 if isinstance(mean_free_path, (int, float)) else mean_free_path
    sigma_t = [1.0 / m for m in mfp]
    scale = max(sigma_t)
    return {"type": "homogeneous", "albedo": _rgb(albedo),
            "sigma_t": _rgb([s / scale for s in sigma_t]), "scale": scale,
            "phase": {"type": "hg", "g": g}}


def _filled(center, radius, bsdf, medium):
    s = _sphere(center, radius, bsdf)
    s["interior"] = medium
    return s


def media(mi, width, height, spp):
    glass = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    matched = {"type": "null"}
    grey = _medium(0.9, 0.5)
    return {
        "type": "scene",
        "camera": _camera(mi, [0, -6, 2], [0, 0, 0.55], 30, width, height, spp),
        "floor": _box(mi, [0, 0, -0.05], [10, 10, 0.1], _diffuse(0.6)),
        "glass": _filled([-1.65, 0, 0.5], 0.5, glass, grey),
        "matched": _filled([-0.55, 0, 0.5], 0.5, matched, grey),
        "forward": _filled([0.55, 0, 0.5], 0.5, matched, _medium(0.95, 0.33, 0.7)),
        "chromatic": _filled([1.65, 0, 0.5], 0.5, matched,
                             _medium([0.95, 0.8, 0.6], [1.0, 0.4, 0.2])),
        "rect": _rect_light(mi, [-1.5, 1.5, 3], [3, 0, 0], [0, -2, 0], 3),
        "bulb": _sphere_light([2, -2, 1.6], 0.2, [30, 24, 16]),
    }


SCENES = {"diffuse": diffuse, "conductors": conductors, "room": room, "media": media}
