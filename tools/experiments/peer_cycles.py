#!/usr/bin/env python3
"""envtrace against Blender Cycles (bpy, CPU): the time each needs to reach the same error on
scene files of envtrace's format, with and without Cycles' path guiding.

Prerequisite, not installed by tools/setup (bpy is about 400 MB and only this experiment uses it;
PyPI's bpy 5.2.3 needs Python 3.13, which pyenv provides):

    ~/.pyenv/versions/3.13.0/bin/python -m venv build/cycles-venv
    build/cycles-venv/bin/pip install bpy==5.2.3 numpy

    build/cycles-venv/bin/python tools/experiments/peer_cycles.py [--quick] [--seeds 3]
        [--scenes A.json B.json ...] [--size 128 96] [--budgets 1 3 9] [--ref-seconds 60] [--out DIR]

It exits 77 (skipped) in a Python without bpy. Defaults: three held-out scenes (scene_set.py's
room002_d5, a window-lit room at depth 5; room006_d1, a room at depth 1; open003_d5, a glass
statue under the open sky), from ENVTRACE_HELDOUT (default /work/heldout).

The conversion (build_blender_scene) reads the scene JSON itself: the same triangles (OBJ
polygons split as envtrace's loader splits them, quads by their shorter diagonal; vertex normals
where the file has them, else flat), the same pinhole camera (vertical field of view) and pixels
(Cycles' box filter of width 1 = envtrace's mean over the pixel), the same map file in an
Environment Texture (linear interpolation between texel centres, as envtrace's bilinear lookup),
turned by a Mapping node so that each direction sees the same texel (conventions.md: Cycles' u is
envtrace's minus a quarter turn), and the path depth: envtrace's max_depth d counts the surfaces
of a path (1 = direct light), Cycles' max_bounces counts the bounces after the first hit, so
Cycles gets d - 1 (every per-type bounce limit too). No clamping, no glossy filter, no light
threshold, no adaptive sampling, no denoising, film not transparent, two threads on both.
Materials (how exact each is):

  diffuse             Diffuse BSDF                                  exact (Lambertian)
  conductor           Metallic BSDF, physical conductor, GGX,       exact (complex Fresnel per
                      IOR = eta, extinction = k, roughness sqrt(a)   RGB channel, single-scatter GGX)
  microfacet, albedo 0  Metallic BSDF, F82 tint, base = specular,   exact (the F82 model with a
  / mirror            edge tint 1, GGX, roughness sqrt(a) (0)        white tint is Schlick's)
  dielectric          Glass BSDF, GGX, IOR, roughness sqrt(a),      exact for tint 1 (Cycles' colour
                      colour = tint                                  tints reflection too)
  plastic / microfacet  Principled BSDF, GGX, roughness sqrt(a),    approximate: a dielectric
  with albedo         IOR from F0 = specular's mean                 Fresnel layer over Lambert with
                                                                     Cycles' own energy compensation,
                                                                     not Schlick + Kelemen's base
Textures, spheres, PLY/glTF meshes and procedural skies are not converted (a clear error).

Per scene: references (envtrace mis, Cycles without guiding; two halves of --ref-seconds / 2 with
different seeds each: their mean is the reference, half their difference its noise), compared
with each other (the conversion's check: image-mean ratio, 16 x 16 block differences against the
references' noise); a direct view of the map alone (all geometry hidden) checks the map's
orientation. Then a ladder of sample counts per method ({envtrace auto, envtrace mis, Cycles,
Cycles + guiding}), each chosen from a calibration render to take about each --budgets seconds,
--seeds seeds, the methods alternating render by render. Each render is measured against its own
renderer's reference with efficiency.py's relative MSE (per pixel channel (x - ref)^2 / (ref^2 +
(0.01 mean ref)^2), mean over the image, less the reference's own noise) and timed: envtrace by
render_seconds of --stats (the pass loop, not loading), Cycles by the render call with persistent
data after a warm-up render (so its scene sync and BVH build, reported apart, are not counted).
The target error is envtrace mis's error at --target-seconds (4 s; log-log interpolation of its
ladder); each method's time to reach it is interpolated in log-log between the rungs around it,
or extrapolated from the nearest rung as error ~ c / time, per seed; the table gives the median
over seeds and the range.

Writes OUT/peer_cycles.md and OUT/peer_cycles.csv (default docs/figures/peer_cycles/)."""
import csv
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

HELDOUT = os.environ.get("ENVTRACE_HELDOUT", "/work/heldout")
DEFAULT_SCENES = ["room002_d5.json", "room006_d1.json", "open003_d5.json"]
METHODS = ["envtrace auto", "envtrace mis", "cycles", "cycles guiding"]
REF_SEEDS = (7919, 7920)
BLOCK = 16
# Envtrace's lat-long u against Cycles': u_cycles = u_envtrace - 1/4 (conventions.md), and each
# convention's map is envtrace's turned by this many degrees.
CONVENTION_TURN = {"envtrace": 0.0, "blender": 90.0, "mitsuba": 180.0}


# --materials-check: the held-out open007_d1 (museum_wells6.exr, a gold Suzanne) with the statue's
# material replaced, one scene per mapping of the docstring's table, plus open003_d5's glass
# Suzanne flat-shaded (its vertex normals dropped) and room004_d1 (a rough silver bunny in a room).
MATERIAL_VARIANTS = {
    "gold_a0.05_d1": ("open007_d1.json", None, None),
    "schlick_a0.1_d1": ("open007_d1.json", {"type": "microfacet", "specular": [0.9, 0.6, 0.3], "roughness": 0.1}, None),
    "mirror_d1": ("open007_d1.json", {"type": "mirror", "specular": [0.9, 0.9, 0.9]}, None),
    "plastic_a0.1_d1": ("open007_d1.json", {"type": "plastic", "albedo": [0.8, 0.3, 0.2], "roughness": 0.1}, None),
    "rough_glass_a0.3_d8": ("open007_d1.json", {"type": "dielectric", "ior": 1.5, "roughness": 0.3}, 8),
    "glass_flat_suzanne_d5": ("open003_d5.json", "flat", None),
    "room004_silver_a0.3_d1": ("room004_d1.json", None, None),
}


def material_variants(work):
    """The scene files of --materials-check, written into `work`."""
    out = []
    for name, (base, mat, depth) in MATERIAL_VARIANTS.items():
        src = os.path.join(HELDOUT, base)
        with open(src) as f:
            s = json.load(f)
        for sh in s["shapes"]:
            if "file" in sh and os.path.isfile(os.path.join(HELDOUT, sh["file"])):
                sh["file"] = os.path.join(HELDOUT, sh["file"])
        if mat == "flat":
            mesh = resolve(s["shapes"][1]["file"], HELDOUT)
            flat = os.path.join(work, "flat_" + os.path.basename(mesh))
            with open(mesh) as f, open(flat, "w") as o:
                for line in f:
                    if not line.startswith("vn "):
                        o.write(" ".join(w.split("/")[0] for w in line.split()) + "\n"
                                if line.startswith("f ") else line)
            s["shapes"][1]["file"] = flat
        elif mat:
            s["materials"]["statue0"] = mat
        if depth:
            s["render"]["max_depth"] = depth
        path = os.path.join(work, name + ".json")
        with open(path, "w") as f:
            json.dump(s, f, indent=1)
        out.append(path)
    return out


# ----------------------------------------------------------------------------- scene reading

def resolve(path, scene_dir):
    """A file of the scene as envtrace resolves it: the scene's folder, then the data folder."""
    for base in (scene_dir, common.data_dir()):
        p = os.path.join(base, path)
        if os.path.isfile(p):
            return os.path.abspath(p)
    sys.exit(f"peer_cycles: {path}: not found beside the scene or in {common.data_dir()}")


def transform_of(shape, where):
    """The shape's 4 x 4 affine matrix (scene-format.md: matrix, or scale, rotate, translate)."""
    t = shape.get("transform", {})
    if "matrix" in t:
        return np.array(t["matrix"], float).reshape(4, 4)
    m = np.eye(4)
    s = t.get("scale", 1.0)
    m[:3, :3] = np.diag(np.broadcast_to(np.array(s, float), 3))
    if "rotate" in t:
        ax, ay, az, deg = t["rotate"]
        a = np.array([ax, ay, az], float)
        a /= np.linalg.norm(a)
        th = math.radians(deg)
        k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        r = np.eye(3) + math.sin(th) * k + (1 - math.cos(th)) * k @ k
        m[:3, :3] = r @ m[:3, :3]
    if "translate" in t:
        m[:3, 3] = t["translate"]
    unknown = set(t) - {"matrix", "scale", "rotate", "translate"}
    if unknown:
        sys.exit(f"peer_cycles: {where}: transform keys {sorted(unknown)} not understood")
    return m


def read_mtl(path):
    """name -> envtrace material dict, as obj_loader.cpp maps MTL keys (no textures)."""
    mats, cur = {}, None
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w or w[0].startswith("#"):
                continue
            if w[0] == "newmtl":
                cur = mats.setdefault(w[1], {"Kd": [0.0] * 3, "Ks": [0.0] * 3, "Ns": 0.0, "illum": 2,
                                            "Ni": 1.5, "Tf": [0.0] * 3, "Pr": 0.0})
            elif cur is not None and w[0] in ("Kd", "Ks", "Tf"):
                cur[w[0]] = [float(x) for x in w[1:4]]
            elif cur is not None and w[0] in ("Ns", "Ni", "Pr"):
                cur[w[0]] = float(w[1])
            elif cur is not None and w[0] == "illum":
                cur["illum"] = int(w[1])
            elif cur is not None and w[0].startswith("map_"):
                sys.exit(f"peer_cycles: {path}: texture maps ({w[0]}) are not converted")
    out = {}
    for name, m in mats.items():
        clamp = lambda c: [min(max(x, 0.0), 1.0) for x in c]  # noqa: E731
        if m["illum"] in (4, 6, 7):
            tf = clamp(m["Tf"])
            out[name] = {"type": "dielectric", "ior": m["Ni"] if m["Ni"] > 1 else 1.5,
                         "roughness": m["Pr"] if m["Pr"] >= 1e-3 else 0.0,
                         "tint": tf if max(tf) > 0 else [1.0] * 3}
        elif max(m["Ks"]) > 0:
            out[name] = {"type": "microfacet", "albedo": clamp(m["Kd"]), "specular": clamp(m["Ks"]),
                         "roughness": min(max(math.sqrt(2 / (max(m["Ns"], 0) + 2)), 0.01), 1.0)}
        else:
            out[name] = {"type": "diffuse", "albedo": clamp(m["Kd"])}
    return out


def read_obj(path):
    """Triangles of an OBJ as envtrace's loader (tinyobjloader) splits them: quads along the shorter
    diagonal, larger polygons as fans. Returns positions (n, 3, 3), each triangle's corner normals
    (3 x 3) or None, each triangle's MTL material name, and the MTL's materials by name."""
    v, vn, tris, nrm, mat_of, mtl = [], [], [], [], [], {}
    cur = None
    folder = os.path.dirname(path)
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                v.append([float(x) for x in w[1:4]])
            elif w[0] == "vn":
                vn.append([float(x) for x in w[1:4]])
            elif w[0] == "usemtl":
                cur = w[1] if len(w) > 1 else None
            elif w[0] == "mtllib":
                p = os.path.join(folder, " ".join(w[1:]))
                if os.path.isfile(p):
                    mtl.update(read_mtl(p))
            elif w[0] == "f":
                corners = []
                for c in w[1:]:
                    parts = c.split("/")
                    vi = int(parts[0])
                    ni = int(parts[2]) if len(parts) > 2 and parts[2] else None
                    vi = vi - 1 if vi > 0 else len(v) + vi
                    if ni is not None:
                        ni = ni - 1 if ni > 0 else len(vn) + ni
                    corners.append((vi, ni))
                if len(corners) == 4:
                    p = [np.array(v[c[0]]) for c in corners]
                    if ((p[2] - p[0]) ** 2).sum() < ((p[3] - p[1]) ** 2).sum():
                        split = [(0, 1, 2), (0, 2, 3)]
                    else:
                        split = [(0, 1, 3), (1, 2, 3)]
                else:
                    split = [(0, i, i + 1) for i in range(1, len(corners) - 1)]
                for t in split:
                    cs = [corners[i] for i in t]
                    tris.append([v[c[0]] for c in cs])
                    nrm.append([vn[c[1]] for c in cs] if all(c[1] is not None for c in cs) else None)
                    mat_of.append(cur)
    return np.array(tris, float), nrm, mat_of, mtl


def load_scene(path, size):
    """The scene JSON and the triangles of its shapes in envtrace's world (y up): a list of
    (positions (n, 3, 3), normals (n, 3, 3) or None, material dict) groups."""
    with open(path) as f:
        s = json.load(f)
    here = os.path.dirname(os.path.abspath(path))
    mats = s.get("materials", {})
    default = {"type": "diffuse", "albedo": [0.8] * 3}
    groups = []
    for i, sh in enumerate(s.get("shapes", [])):
        where = f"{path}: shapes[{i}]"
        named = mats.get(sh["material"]) if "material" in sh else None
        if "material" in sh and named is None:
            sys.exit(f"peer_cycles: {where}: unknown material {sh['material']}")
        m = transform_of(sh, where)
        if sh["type"] == "quad":
            hx, hz = (np.broadcast_to(np.array(sh.get("size", 10.0), float), 2) / 2)
            c = np.array(sh.get("center", [0, 0, 0]), float)
            q = [c + [-hx, 0, -hz], c + [hx, 0, -hz], c + [hx, 0, hz], c + [-hx, 0, hz]]
            tris = np.array([[q[0], q[2], q[1]], [q[0], q[3], q[2]]])
            if np.linalg.det(m[:3, :3]) < 0:
                tris = tris[:, [0, 2, 1]]
            groups.append((apply(m, tris), None, named or default))
        elif sh["type"] == "mesh":
            f = resolve(sh["file"], here)
            if not f.lower().endswith(".obj"):
                sys.exit(f"peer_cycles: {where}: only OBJ meshes are converted, not {f}")
            tris, nrm, mat_of, mtl = read_obj(f)
            # Triangles with and without normals, per material: one Blender object each.
            keys = sorted(set((mo, n is not None) for mo, n in zip(mat_of, nrm)), key=str)
            for mo, has_n in keys:
                sel = [k for k in range(len(tris)) if mat_of[k] == mo and (nrm[k] is not None) == has_n]
                mat = named or mtl.get(mo, default)
                normals = None
                if has_n:
                    nm = np.linalg.inv(m[:3, :3]).T
                    normals = np.array([nrm[k] for k in sel]) @ nm.T
                    normals /= np.maximum(np.linalg.norm(normals, axis=2, keepdims=True), 1e-30)
                t = apply(m, tris[sel])
                if np.linalg.det(m[:3, :3]) < 0:  # mirrored: keep front faces (scene-format.md)
                    t = t[:, [0, 2, 1]]
                    normals = normals[:, [0, 2, 1]] if normals is not None else None
                groups.append((t, normals, mat))
        else:
            sys.exit(f"peer_cycles: {where}: shape type {sh['type']} is not converted (mesh, quad)")
    env = s["environment"]
    if "map" not in env:
        sys.exit(f"peer_cycles: {path}: environment.sky is not converted (a scene with a map file)")
    env = dict(env, map=resolve(env["map"], here))
    s["environment"] = env
    s["film"] = {"width": size[0], "height": size[1]}
    for sh in s.get("shapes", []):
        if "file" in sh:
            sh["file"] = resolve(sh["file"], here)
    s.pop("output", None)
    return s, groups


def apply(m, tris):
    return tris @ m[:3, :3].T + m[:3, 3]


def to_blender(p):
    """envtrace's y-up (x, y, z) -> Blender's z-up (x, -z, y): a rotation (det +1), the one
    Blender's OBJ exporter with +Y up undoes, under which conventions.md relates the maps."""
    p = np.asarray(p, float)
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], -1)


# ----------------------------------------------------------------------------- Blender scene

def empty_node_tree(owner):
    """A material's or world's node tree, emptied (Blender 5 always has one: use_nodes is gone)."""
    try:
        owner.use_nodes = True
    except AttributeError:
        pass
    owner.node_tree.nodes.clear()
    return owner.node_tree


def node_material(bpy, name, mat):
    """A Cycles material for an envtrace material (the table of the module docstring)."""
    bm = bpy.data.materials.new(name)
    nt = empty_node_tree(bm)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    t = {"cook-torrance": "microfacet", "metal": "conductor", "glass": "dielectric"}.get(
        mat.get("type", "diffuse"), mat.get("type", "diffuse"))
    col = lambda c, d: list(np.broadcast_to(np.array(c if c is not None else d, float), 3)) + [1.0]  # noqa
    for key in ("albedo", "specular", "roughness"):
        if isinstance(mat.get(key), dict):
            sys.exit(f"peer_cycles: material {name}: texture objects are not converted")
    alpha = float(mat.get("roughness", {"conductor": 0.1, "dielectric": 0.0}.get(t, 0.3)))
    rough = math.sqrt(max(alpha, 0.0))
    if t == "diffuse":
        n = nt.nodes.new("ShaderNodeBsdfDiffuse")
        n.inputs["Color"].default_value = col(mat.get("albedo"), 0.8)
        n.inputs["Roughness"].default_value = 0.0
    elif t == "conductor":
        n = nt.nodes.new("ShaderNodeBsdfMetallic")
        n.fresnel_type, n.distribution = "PHYSICAL_CONDUCTOR", "GGX"
        n.inputs["IOR"].default_value = col(mat.get("eta"), [0.155, 0.117, 0.138])[:3]
        n.inputs["Extinction"].default_value = col(mat.get("k"), [4.828, 3.122, 2.147])[:3]
        n.inputs["Roughness"].default_value = rough
    elif t == "mirror" or (t == "microfacet" and max(col(mat.get("albedo"), 0.0)[:3]) == 0):
        n = nt.nodes.new("ShaderNodeBsdfMetallic")
        n.fresnel_type, n.distribution = "F82", "GGX"
        n.inputs["Base Color"].default_value = col(mat.get("specular"), 1.0 if t == "mirror" else 0.04)
        n.inputs["Edge Tint"].default_value = [1.0, 1.0, 1.0, 1.0]
        n.inputs["Roughness"].default_value = 0.0 if t == "mirror" else rough
    elif t == "dielectric":
        n = nt.nodes.new("ShaderNodeBsdfGlass")
        n.distribution = "GGX"
        n.inputs["Color"].default_value = col(mat.get("tint"), 1.0)
        n.inputs["IOR"].default_value = float(mat.get("ior", 1.5))
        n.inputs["Roughness"].default_value = rough if alpha >= 1e-3 else 0.0
    elif t in ("plastic", "microfacet"):
        n = nt.nodes.new("ShaderNodeBsdfPrincipled")
        n.distribution = "GGX"
        f0 = float(np.mean(col(mat.get("specular"), 0.04)[:3]))
        n.inputs["Base Color"].default_value = col(mat.get("albedo"), 0.5)
        n.inputs["Roughness"].default_value = rough
        n.inputs["IOR"].default_value = (1 + math.sqrt(f0)) / max(1 - math.sqrt(f0), 1e-3)
        n.inputs["Specular IOR Level"].default_value = 0.5
        n.inputs["Metallic"].default_value = 0.0
    else:
        sys.exit(f"peer_cycles: material {name}: type {t} is not converted")
    nt.links.new(n.outputs[0], out.inputs["Surface"])
    return bm


def blender_mesh(bpy, name, tris, normals, material):
    """One Blender object of separate triangles (positions in Blender's frame), with the file's
    vertex normals as custom normals (smooth shading) or flat."""
    p = to_blender(tris).reshape(-1, 3)
    n = len(tris)
    me = bpy.data.meshes.new(name)
    me.vertices.add(3 * n)
    me.vertices.foreach_set("co", p.astype(np.float32).ravel())
    me.loops.add(3 * n)
    me.loops.foreach_set("vertex_index", np.arange(3 * n, dtype=np.int32))
    me.polygons.add(n)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * n, 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(n, 3, np.int32))
    me.update(calc_edges=True)
    me.validate(verbose=False)
    if normals is not None:
        me.polygons.foreach_set("use_smooth", np.ones(n, bool))
        me.normals_split_custom_set(to_blender(normals).reshape(-1, 3).tolist())
    else:
        me.polygons.foreach_set("use_smooth", np.zeros(n, bool))
    me.materials.append(material)
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def build_blender_scene(bpy, scene, groups, depth, pattern, rr_depth):
    """The converted scene in a fresh Blender file; returns the Blender scene and its objects."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bs = bpy.context.scene
    bs.render.engine = "CYCLES"
    cy = bs.cycles
    cy.device = "CPU"
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.max_bounces = depth - 1
    for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "transparent_max_bounces"):
        setattr(cy, k, depth - 1)
    cy.volume_bounces = 0
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.caustics_reflective = cy.caustics_refractive = True
    cy.light_sampling_threshold = 0.0
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.use_guiding = False
    cy.use_surface_guiding = True
    cy.use_volume_guiding = False
    cy.sampling_pattern = pattern
    # Russian roulette: envtrace's rr_depth (surfaces before roulette may end a path) as Cycles'
    # minimum light bounces; None keeps Cycles' own (roulette from the first bounce).
    if rr_depth is not None:
        cy.min_light_bounces = rr_depth
    bs.render.film_transparent = False
    bs.render.threads_mode = "FIXED"
    bs.render.threads = 2
    bs.render.use_persistent_data = True
    bs.render.resolution_x, bs.render.resolution_y = scene["film"]["width"], scene["film"]["height"]
    bs.render.resolution_percentage = 100
    bs.render.pixel_aspect_x = bs.render.pixel_aspect_y = 1.0
    bs.view_settings.view_transform = "Standard"
    bs.view_settings.look = "None"
    bs.view_settings.exposure, bs.view_settings.gamma = 0.0, 1.0
    bs.render.image_settings.file_format = "OPEN_EXR"
    bs.render.image_settings.color_depth = "32"
    bs.render.image_settings.exr_codec = "NONE"

    # Camera: envtrace's look-at frame (right = forward x up), Blender's camera looks down -Z.
    cam = scene.get("camera", {})
    eye = np.array(cam.get("eye", [0, 1, 4]), float)
    f = np.array(cam.get("target", [0, 0, 0]), float) - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, np.array(cam.get("up", [0, 1, 0]), float))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rot = to_blender(np.stack([r, u, -f], 0)).T  # columns: the camera's X, Y, Z in Blender's frame
    cd = bpy.data.cameras.new("camera")
    cd.type = "PERSP"
    cd.sensor_fit = "VERTICAL"
    cd.angle_y = math.radians(cam.get("fov", 40.0))
    cd.clip_start, cd.clip_end = 1e-5, 1e8
    co = bpy.data.objects.new("camera", cd)
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot, to_blender(eye)
    import mathutils
    co.matrix_world = mathutils.Matrix(m.tolist())
    bs.collection.objects.link(co)
    bs.camera = co

    # World: the map, turned so that a direction sees the texel it sees in envtrace. envtrace
    # looks the map up at Ry(rotation) d (a right-handed turn about +Y, which is Blender's +Z),
    # Cycles at u_envtrace - 1/4; so Cycles' lookup vector is turned by rotation - 90 degrees.
    env = scene["environment"]
    turn = float(env.get("rotation", 0.0)) + CONVENTION_TURN[env.get("convention", "envtrace")]
    w = bpy.data.worlds.new("world")
    bs.world = w
    nt = empty_node_tree(w)
    tc = nt.nodes.new("ShaderNodeTexCoord")
    mp = nt.nodes.new("ShaderNodeMapping")
    mp.vector_type = "POINT"
    mp.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(turn - 90.0))
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(env["map"])
    tex.image.colorspace_settings.name = "Linear Rec.709"
    tex.interpolation = "Linear"
    tex.projection = "EQUIRECTANGULAR"
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = float(env.get("intensity", 1.0))
    wo = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(tc.outputs["Generated"], mp.inputs["Vector"])
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], wo.inputs["Surface"])

    objects, cache = [], {}
    for i, (tris, normals, mat) in enumerate(groups):
        key = json.dumps(mat, sort_keys=True)
        if key not in cache:
            cache[key] = node_material(bpy, f"mat{len(cache)}", mat)
        objects.append(blender_mesh(bpy, f"shape{i}", tris, normals, cache[key]))
    return bs, objects


class Cycles:
    """The converted scene, rendered again and again (persistent data: synced once)."""

    def __init__(self, bpy, scene, groups, depth, work, name, pattern, rr_depth):
        self.bpy, self.work, self.name = bpy, work, name
        t0 = time.perf_counter()
        self.bs, self.objects = build_blender_scene(bpy, scene, groups, depth, pattern, rr_depth)
        self.build_seconds = time.perf_counter() - t0
        _, self.sync_seconds = self.render(1, 1, False)  # the first render syncs and builds the BVH

    def render(self, spp, seed, guiding):
        cy = self.bs.cycles
        cy.samples, cy.seed, cy.use_guiding = int(spp), int(seed), bool(guiding)
        t0 = time.perf_counter()
        self.bpy.ops.render.render(write_still=False)
        seconds = time.perf_counter() - t0
        path = os.path.join(self.work, f"{self.name}-cycles.exr")
        self.bpy.data.images["Render Result"].save_render(path)
        img = self.bpy.data.images.load(path, check_existing=False)
        w, h = img.size
        px = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(px)
        self.bpy.data.images.remove(img)
        return px.reshape(h, w, 4)[::-1, :, :3].astype(np.float64), seconds

    def hide_geometry(self, hidden):
        for ob in self.objects:
            ob.hide_render = hidden


# ----------------------------------------------------------------------------- envtrace

def envtrace_render(scene_path, work, name, strategy, seed, spp=None, seconds=None, extra=()):
    out = os.path.join(work, f"{name}-envtrace.pfm")
    args = ["--spp", str(int(spp))] if spp else ["--time-limit", str(seconds)]
    stats = common.render(scene_path, out, args + ["--seed", str(seed), "--strategy", strategy,
                                                   "--threads", "2"] + list(extra))
    return common.read_pfm(out), stats


# ----------------------------------------------------------------------------- measures

def rel_error(img, ref, ref_var):
    """efficiency.py's relative MSE, less the reference's own noise."""
    denom = ref ** 2 + (0.01 * float(ref.mean())) ** 2
    err = (np.nan_to_num(img, nan=0.0, posinf=0.0) - ref) ** 2 / denom
    return max(float(err.mean()) - float((ref_var / denom).mean()), 0.0)


def blocks(img, n=BLOCK):
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    return img[:h, :w].mean(axis=2).reshape(h // n, n, w // n, n).mean(axis=(1, 3))


def agreement(a, a_var, b, b_var):
    """envtrace's image a against Cycles' b (each with the variance of its mean): the ratio of the
    image means per channel, and per block the relative difference and its z-score."""
    ratio = a.mean(axis=(0, 1)) / np.maximum(b.mean(axis=(0, 1)), 1e-30)
    ba, bb = blocks(a), blocks(b)
    se = np.sqrt(blocks(a_var) / BLOCK ** 2 + blocks(b_var) / BLOCK ** 2)  # pixels independent
    rel = (ba - bb) / np.maximum(np.abs(bb), 1e-30)
    z = (ba - bb) / np.maximum(se, 1e-30)
    return {"ratio": ratio, "mean_ratio": float(a.mean() / max(b.mean(), 1e-30)),
            "block_rel_rms": float(np.sqrt((rel ** 2).mean())), "block_rel_max": float(np.abs(rel).max()),
            "block_z_rms": float(np.sqrt((z ** 2).mean()))}


def interp_time(times, errors, target):
    """Time to reach `target` on a ladder of (time, error), log-log between the rungs around it,
    else error ~ c / time from the nearest rung."""
    pts = sorted((t, e) for t, e in zip(times, errors) if e > 0 and t > 0)
    if not pts:
        return float("nan")
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if min(e0, e1) <= target <= max(e0, e1) and e0 != e1:
            k = math.log(target / e0) / math.log(e1 / e0)
            return math.exp(math.log(t0) + k * math.log(t1 / t0))
    t, e = pts[0] if target > pts[0][1] else pts[-1]
    return t * e / target


def interp_error(times, errors, at):
    """Error at time `at` on a ladder, log-log; beyond it, error ~ c / time."""
    pts = sorted((t, e) for t, e in zip(times, errors) if e > 0 and t > 0)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if t0 <= at <= t1:
            k = math.log(at / t0) / math.log(t1 / t0)
            return math.exp(math.log(e0) + k * math.log(e1 / e0))
    t, e = pts[0] if at < pts[0][0] else pts[-1]
    return e * t / at


def fit_c(times, errors):
    """c of error = c / time over a ladder (least squares in log-log with the slope held at -1)."""
    pts = [t * e for t, e in zip(times, errors) if e > 0 and t > 0]
    return math.exp(np.mean(np.log(pts))) if pts else float("nan")


def log_slope(times, errors):
    """The free log-log slope of error against time (-1 for Monte Carlo; steeper for quasi-Monte
    Carlo; flatter, or erratic, where rare fireflies rule the error)."""
    pts = np.array([(t, e) for t, e in zip(times, errors) if e > 0 and t > 0])
    if len(pts) < 2 or np.ptp(np.log(pts[:, 0])) == 0:
        return float("nan")
    return float(np.polyfit(np.log(pts[:, 0]), np.log(pts[:, 1]), 1)[0])


# ----------------------------------------------------------------------------- the experiment

def measure_scene(bpy, path, a, work):
    name = os.path.splitext(os.path.basename(path))[0]
    scene, groups = load_scene(path, a.size)
    depth = int(scene.get("render", {}).get("max_depth", 12))
    scene.setdefault("render", {}).pop("spp", None)
    et_scene = os.path.join(work, f"{name}.json")
    with open(et_scene, "w") as f:
        json.dump(scene, f, indent=1)
    empty = dict(scene, shapes=[], materials={})
    et_empty = os.path.join(work, f"{name}-map.json")
    with open(et_empty, "w") as f:
        json.dump(empty, f, indent=1)
    rr = int(scene.get("render", {}).get("rr_depth", 5)) if a.cycles_rr == "envtrace" else None
    cy = Cycles(bpy, scene, groups, depth, work, name, a.cycles_pattern, rr)
    print(f"{name}: depth {depth}, {sum(len(g[0]) for g in groups)} triangles; Blender build "
          f"{cy.build_seconds:.2f} s, first render (sync + BVH + 1 spp) {cy.sync_seconds:.2f} s", flush=True)
    res = {"scene": name, "depth": depth, "cycles_build_s": cy.build_seconds, "cycles_sync_s": cy.sync_seconds}

    # The map alone, seen directly: the orientation check (no transport involved).
    cy.hide_geometry(True)
    cm, _ = cy.render(a.map_spp, 1, False)
    cy.hide_geometry(False)
    cy.render(1, 1, False)  # re-sync the geometry outside any timing
    em, _ = envtrace_render(et_empty, work, name + "-map", "mis", 1, spp=a.map_spp)
    mrel = (blocks(em) - blocks(cm)) / np.maximum(blocks(cm), 1e-30)
    res["map"] = {"mean_ratio": float(em.mean() / cm.mean()), "block_rel_rms": float(np.sqrt((mrel ** 2).mean())),
                  "block_rel_max": float(np.abs(mrel).max())}
    print(f"{name}: map alone, envtrace / cycles mean {res['map']['mean_ratio']:.4f}, 16x16 blocks "
          f"rel rms {res['map']['block_rel_rms']:.4f} max {res['map']['block_rel_max']:.4f}", flush=True)

    # Calibration: seconds per sample of each method.
    rate = {}
    for m in ["cycles"] if a.agreement_only else METHODS:
        if m.startswith("envtrace"):
            _, st = envtrace_render(et_scene, work, name, m.split()[1], 1, seconds=a.calibrate_seconds)
            rate[m] = st["spp"] / st["render_seconds"]
        else:
            n = 4
            while True:
                _, s = cy.render(n, 1, m.endswith("guiding"))
                if s >= a.calibrate_seconds / 2 or n >= 1 << 16:
                    break
                n *= 4
            rate[m] = n / s
    print(f"{name}: samples per second " + ", ".join(f"{m} {r:.1f}" for m, r in rate.items()), flush=True)

    # References: two halves each, envtrace mis and Cycles without guiding.
    halves = {"envtrace": [], "cycles": []}
    ref_s = {"envtrace": 0.0, "cycles": 0.0}
    ref_spp = {"envtrace": 0, "cycles": 0}
    for seed in REF_SEEDS:
        img, st = envtrace_render(et_scene, work, f"{name}-ref{seed}", "mis", seed, seconds=a.ref_seconds / 2)
        halves["envtrace"].append(img)
        ref_s["envtrace"] += st["render_seconds"]
        ref_spp["envtrace"] += st["spp"]
        n = max(1, int(rate["cycles"] * a.ref_seconds / 2))
        img, s = cy.render(n, seed, False)
        halves["cycles"].append(img)
        ref_s["cycles"] += s
        ref_spp["cycles"] += n
    refs = {}
    for k, (h0, h1) in halves.items():
        refs[k] = (0.5 * (h0 + h1), 0.25 * (h0 - h1) ** 2)
    res["refs"] = agreement(*refs["envtrace"], *refs["cycles"])
    res["ref_spp"], res["ref_s"] = ref_spp, ref_s
    g = res["refs"]
    print(f"{name}: references ({ref_spp['envtrace']} / {ref_spp['cycles']} spp): envtrace / cycles "
          f"mean {g['mean_ratio']:.4f} (R G B {' '.join(f'{x:.4f}' for x in g['ratio'])}), 16x16 blocks "
          f"rel rms {g['block_rel_rms']:.4f} max {g['block_rel_max']:.4f}, z rms {g['block_z_rms']:.2f}", flush=True)
    np.save(os.path.join(work, f"{name}-ref-envtrace.npy"), refs["envtrace"][0])
    np.save(os.path.join(work, f"{name}-ref-cycles.npy"), refs["cycles"][0])

    if a.agreement_only:
        return res

    # The ladder: methods alternate render by render.
    rows = []
    for budget in a.budgets:
        for seed in range(1, a.seeds + 1):
            for m in METHODS:
                spp = max(1, int(round(rate[m] * budget)))
                if m.startswith("envtrace"):
                    img, st = envtrace_render(et_scene, work, name, m.split()[1], seed, spp=spp)
                    secs, ref = st["render_seconds"], refs["envtrace"]
                else:
                    img, secs = cy.render(spp, seed, m.endswith("guiding"))
                    ref = refs["cycles"]
                e = rel_error(img, *ref)
                rows.append({"scene": name, "method": m, "budget": budget, "seed": seed, "spp": spp,
                             "seconds": secs, "rel_mse": e})
                print(f"{name} {m:>15} {budget:g}s seed {seed}: {spp} spp {secs:.2f} s rel MSE {e:.4g}", flush=True)
    res["rows"] = rows

    # Target: envtrace mis's error at target-seconds; each method's time to reach it.
    def ladder(m, seed):
        rs = [r for r in rows if r["method"] == m and r["seed"] == seed]
        return [r["seconds"] for r in rs], [r["rel_mse"] for r in rs]

    seeds = range(1, a.seeds + 1)
    target = float(np.median([interp_error(*ladder("envtrace mis", s), a.target_seconds) for s in seeds]))
    res["target"] = target
    res["times"] = {}
    for m in METHODS:
        ts = [interp_time(*ladder(m, s), target) for s in seeds]
        inside = []
        for s in seeds:
            es = ladder(m, s)[1]
            inside.append(min(es) <= target <= max(es))
        fit = [fit_c(*ladder(m, s)) / target for s in seeds]
        t_all, e_all = zip(*[(r["seconds"], r["rel_mse"]) for r in rows if r["method"] == m])
        res["times"][m] = {"median": float(np.median(ts)), "min": float(min(ts)), "max": float(max(ts)),
                           "interpolated": all(inside), "fit": float(np.median(fit)),
                           "slope": log_slope(t_all, e_all)}
    print(f"{name}: target rel MSE {target:.4g}: " + ", ".join(
        f"{m} {v['median']:.2f} s" for m, v in res["times"].items()), flush=True)
    return res


def write_agreement(results, a, out, bpy_version):
    """--agreement-only: the conversion's table alone."""
    L = [f"# envtrace against Cycles {bpy_version}: the conversion\n",
         f"`build/cycles-venv/bin/python tools/experiments/peer_cycles.py "
         f"{'--materials-check' if a.materials_check else '--agreement-only'} --ref-seconds "
         f"{a.ref_seconds:g} --size {a.size[0]} {a.size[1]} --cycles-rr {a.cycles_rr}` (scenes: "
         f"{', '.join(os.path.basename(s) for s in a.scenes)})\n"]
    L += agreement_table(results, a)
    with open(os.path.join(out, "agreement.md"), "w") as f:
        f.write("\n".join(L) + "\n")
    print(f"wrote {os.path.join(out, 'agreement.md')}")


def agreement_table(results, a):
    L = ["Each renderer's reference (envtrace mis, Cycles without guiding; two halves of "
         f"{a.ref_seconds / 2:g} s each). Mean ratio envtrace / Cycles over the image and per channel; "
         f"{BLOCK}x{BLOCK}-pixel blocks: relative difference (rms, max) and z-score against both "
         "references' noise (rms). \"map alone\": every shape hidden, the map seen directly "
         f"({a.map_spp} spp each).\n",
         "| scene | ref spp envtrace / Cycles | mean ratio | R / G / B | block rel rms | block rel max | "
         "block z rms | map alone: mean ratio, block rel rms / max | Cycles build / first render s |",
         "|---|---|---|---|---|---|---|---|---|"]
    for res in results:
        g, mp = res["refs"], res["map"]
        L.append(f"| {res['scene']} | {res['ref_spp']['envtrace']} / {res['ref_spp']['cycles']} | "
                 f"{g['mean_ratio']:.4f} | {' / '.join(f'{x:.4f}' for x in g['ratio'])} | "
                 f"{g['block_rel_rms']:.4f} | {g['block_rel_max']:.4f} | {g['block_z_rms']:.2f} | "
                 f"{mp['mean_ratio']:.4f}, {mp['block_rel_rms']:.4f} / {mp['block_rel_max']:.4f} | "
                 f"{res['cycles_build_s']:.2f} / {res['cycles_sync_s']:.2f} |")
    return L


def write_report(results, a, out, bpy_version):
    rows = [r for res in results for r in res["rows"]]
    with open(os.path.join(out, "peer_cycles.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    cmd = (f"build/cycles-venv/bin/python tools/experiments/peer_cycles.py --seeds {a.seeds} "
           f"--budgets {' '.join(f'{b:g}' for b in a.budgets)} --ref-seconds {a.ref_seconds:g} "
           f"--size {a.size[0]} {a.size[1]} --cycles-pattern {a.cycles_pattern} --cycles-rr {a.cycles_rr}" + (" --quick" if a.quick else ""))
    L = [f"# envtrace against Cycles {bpy_version} at equal error\n",
         f"`{cmd}` (scenes: {', '.join(os.path.basename(s) for s in a.scenes)}); both on the CPU with "
         f"2 threads, box-filtered pixels, {a.size[0]}x{a.size[1]}, on a 2-core host shared with other "
         f"work (times are medians of alternating renders, {a.seeds} seeds).\n",
         "## Time to reach envtrace mis's error at "
         f"{a.target_seconds:g} s\n",
         "Seconds of rendering (envtrace: render_seconds; Cycles: the render call after a warm-up, "
         "scene sync and BVH excluded), median over seeds [min-max]; * = extrapolated beyond the "
         "ladder as error ~ c / time. The ratio is to envtrace mis.\n",
         "| scene | target rel MSE | " + " | ".join(METHODS) + " |",
         "|---|---|" + "---|" * len(METHODS)]
    for res in results:
        mis = res["times"]["envtrace mis"]["median"]
        cells = []
        for m in METHODS:
            v = res["times"][m]
            cells.append(f"{v['median']:.2f}{'' if v['interpolated'] else '*'} [{v['min']:.2f}-{v['max']:.2f}] "
                         f"(x{v['median'] / mis:.2f})")
        L.append(f"| {res['scene']} (d{res['depth']}) | {res['target']:.4g} | " + " | ".join(cells) + " |")
    L += ["", "The same target reached by the fit error = c / time over each method's whole ladder "
          "(median over seeds; ratio to envtrace mis's fit), and the free log-log slope of error against "
          "time over all its renders (-1: Monte Carlo; steeper: quasi-Monte Carlo; flatter or erratic: "
          "fireflies rule the error, and the times above are uncertain).\n",
          "| scene | " + " | ".join(METHODS) + " |", "|---|" + "---|" * len(METHODS)]
    for res in results:
        mis = res["times"]["envtrace mis"]["fit"]
        L.append(f"| {res['scene']} | " + " | ".join(
            f"{res['times'][m]['fit']:.2f} s (x{res['times'][m]['fit'] / mis:.2f}), slope {res['times'][m]['slope']:.2f}"
            for m in METHODS) + " |")
    L += ["", "## The conversion: converged references compared\n"] + agreement_table(results, a)
    L += ["", "## Every render\n", "Median over seeds per rung (all renders: peer_cycles.csv).\n",
          "| scene | method | budget s | spp | seconds | rel MSE |", "|---|---|---|---|---|---|"]
    for res in results:
        for m in METHODS:
            for b in a.budgets:
                rs = [r for r in res["rows"] if r["method"] == m and r["budget"] == b]
                L.append(f"| {res['scene']} | {m} | {b:g} | {rs[0]['spp']} | "
                         f"{np.median([r['seconds'] for r in rs]):.2f} | {np.median([r['rel_mse'] for r in rs]):.4g} |")
    with open(os.path.join(out, "peer_cycles.md"), "w") as f:
        f.write("\n".join(L) + "\n")
    print(f"wrote {os.path.join(out, 'peer_cycles.md')}")


def main():
    p = common.parser(__doc__.split("\n\n")[0])
    p.add_argument("--scenes", nargs="+", default=None, help="scene files (default: three held-out scenes)")
    p.add_argument("--size", type=int, nargs=2, default=[128, 96], metavar=("W", "H"))
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--budgets", type=float, nargs="+", default=[1.0, 3.0, 9.0],
                   help="the ladder: seconds each rung's sample count is chosen to take")
    p.add_argument("--ref-seconds", type=float, default=60.0, help="each reference's render time")
    p.add_argument("--target-seconds", type=float, default=4.0, help="the target: envtrace mis's error at this time")
    p.add_argument("--calibrate-seconds", type=float, default=1.0)
    p.add_argument("--map-spp", type=int, default=16)
    p.add_argument("--cycles-pattern", default="AUTOMATIC", choices=["AUTOMATIC", "TABULATED_SOBOL", "BLUE_NOISE"],
                   help="Cycles' sampling pattern (AUTOMATIC, its default: blue noise)")
    p.add_argument("--cycles-rr", default="envtrace", choices=["envtrace", "cycles"],
                   help="Cycles' Russian roulette: from envtrace's rr_depth (min light bounces) or its own")
    p.add_argument("--agreement-only", action="store_true",
                   help="only the conversion's check (map alone, references compared), no ladder")
    p.add_argument("--materials-check", action="store_true",
                   help="--agreement-only on variants of held-out scenes, one per material mapping")
    p.add_argument("--quick", action="store_true", help="a short run: budgets 0.5 2 8, 1 seed, 16 s references")
    a = p.parse_args()
    if a.quick or a.tiny:
        a.budgets, a.seeds, a.ref_seconds, a.calibrate_seconds = [0.5, 2.0, 8.0], 1, 16.0, 0.5
    a.scenes = a.scenes or [os.path.join(HELDOUT, s) for s in DEFAULT_SCENES]
    try:
        import bpy
    except ImportError:
        print("peer_cycles: no bpy module in this Python (see the docstring: build/cycles-venv): "
              "skipping", file=sys.stderr)
        sys.exit(77)
    common.envtrace()
    out = common.out_dir(a, "peer_cycles")
    work = common.tmpdir("peer_cycles")
    if a.materials_check:
        a.scenes, a.agreement_only = material_variants(work), True
    results = [measure_scene(bpy, s, a, work) for s in a.scenes]
    if a.agreement_only:
        write_agreement(results, a, out, bpy.app.version_string)
    else:
        write_report(results, a, out, bpy.app.version_string)


if __name__ == "__main__":
    main()
