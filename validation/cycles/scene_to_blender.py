"""Build a nimbus scene JSON in Blender Cycles and render it (run inside Blender).

    blender -b --factory-startup --python validation/cycles/scene_to_blender.py -- \
        SCENE.json OUT.exr [--samples N] [--seed S] [--threads T] [--npy OUT.npy] [--blend OUT.blend]

Writes a linear float32 RGB OpenEXR (and, with --npy, the same pixels as a (height, width, 3)
float32 array, row 0 = top like nimbus) so that /usr/bin/python3 can compare without OpenEXR.

Mapping (docs/validation/cycles.md explains and checks each line):
  camera       pinhole, sensor fit VERTICAL, angle_y = fov_y_deg; rotation from the nimbus basis
               right = forward x up, up' = right x forward (Blender cameras look down local -Z,
               local +Y up); resolution width x height at 100 %, box pixel filter 1 px wide.
  media        homogeneous only (sphere, box). Volume Scatter gives sigma_s = Color * Density,
               Volume Absorption gives sigma_a = (1 - Color) * Density (Cycles svm_node_closure_volume),
               so Color = sigma/max(sigma), Density = max(sigma) per closure, added with an Add Shader.
               Phase: Anisotropy = HG g; double_hg would be two Volume Scatter closures with
               densities w * sigma_s and (1 - w) * sigma_s, but Cycles 3.4 gets their weights
               wrong (refused unless --allow-multi-lobe). Box = cube mesh (exact); sphere = UV sphere whose
               radius is scaled so that the polyhedron's volume equals the sphere's (deviation reported).
  surfaces     sphere = smooth-shaded UV sphere (same segments, scaled to the sphere's volume);
               rectangle = a 4-vertex plane with width along normal x up, height along up; box =
               cube mesh; mesh = bpy.ops.wm.obj_import with forward_axis Y, up_axis Z (OBJ x, y, z
               = world x, y, z, as nimbus reads it; checked against the file's v lines). diffuse =
               Diffuse BSDF (roughness 0, Color = albedo); holdout = Holdout shader. Cycles surfaces
               are two-sided like nimbus'. Shadow-terminator offsets are set to 0.
               emission (constant only) = an Emission closure in the volume, Strength = max(emission),
               Color = emission / max (Cycles adds it per unit length, as nimbus does).
  transform    on media and surfaces: matrix_world = T R_n ... R_1 S (or the row-major matrix) times
               the shape's own placement.
  directional  SUN lamp, Strength = irradiance (W/m^2), Color = irradiance / max, angle = angular
               diameter (use 0: Cycles' disc radiance is S/(pi tan^2(a/2)), nimbus' S/(pi sin^2(a/2))).
  point        POINT lamp, radius 0, Power P = 4 pi I (Cycles: I = P / (4 pi) W/sr, eval_fac = 1/(4 pi)).
  spot, sphere, rectangle: see build_area_or_spot_light (sphere: build_sphere_light_mesh by default,
               --sphere-lights lamp for a POINT lamp of radius r).
  environment  World Background, Color = radiance, Strength 1 (black world without one). An image
               (`file`): Environment Texture node, EQUIRECTANGULAR, interpolation Closest (nimbus
               reads the nearest pixel), colour space Linear, Strength = intensity; its `transform`
               rotation R (world = R map) through a Mapping node (POINT) rotating the lookup
               direction by R^-1 (Generated coordinates of the world = the ray direction).
  integrator   max_events 0 -> volume bounces 1024; max_events k -> volume bounces k - 1.
"""
import argparse
import json
import math
import sys
from pathlib import Path

import bmesh
import bpy
import numpy as np
from mathutils import Matrix, Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="scene_to_blender.py")
    p.add_argument("scene")
    p.add_argument("output", help="output .exr")
    p.add_argument("--samples", type=int, default=None, help="default: the scene's integrator.spp")
    p.add_argument("--seed", type=int, default=None, help="Cycles seed (default: the scene's seed)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--sphere-segments", type=int, default=256,
                   help="UV sphere segments around (rings = segments / 2)")
    p.add_argument("--npy", default=None, help="also save the pixels as (h, w, 3) float32 .npy")
    p.add_argument("--blend", default=None, help="also save the built .blend (debugging)")
    p.add_argument("--sphere-lights", choices=["lamp", "mesh"], default="mesh",
                   help="sphere lights as emissive, transparent UV spheres (default: exact up to tessellation) "
                        "or as POINT lamps of radius r (Cycles 3.4 samples a disc: dimmer nearby)")
    p.add_argument("--allow-multi-lobe", action="store_true",
                   help="render double_hg as two Volume Scatter closures although Cycles 3.4 gets it wrong")
    return p.parse_args(argv)


ALLOW_MULTI_LOBE = False


def rgb(value):
    """A nimbus number-or-[r, g, b] as a 3-tuple of floats."""
    if isinstance(value, (int, float)):
        return (float(value),) * 3
    if len(value) != 3:
        raise ValueError(f"expected a number or [r, g, b], got {value!r}")
    return tuple(float(v) for v in value)


def color_and_scale(value):
    """Split an RGB coefficient into (colour with max 1, scale = max) as Blender's nodes want."""
    c = rgb(value)
    m = max(c)
    if m <= 0.0:
        return (0.0, 0.0, 0.0), 0.0
    return tuple(v / m for v in c), m


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


# --- Camera -----------------------------------------------------------------------------------
def build_camera(cam):
    scene = bpy.context.scene
    data = bpy.data.cameras.new("camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(cam["fov_y_deg"])
    data.shift_x = data.shift_y = 0.0
    data.clip_start = 1e-4
    data.clip_end = 1e7
    obj = link(bpy.data.objects.new("camera", data))
    pos = Vector(cam["position"])
    forward = (Vector(cam["look_at"]) - pos).normalized()
    right = forward.cross(Vector(cam.get("up", [0, 0, 1]))).normalized()
    up = right.cross(forward)
    # Blender camera: local +X right, +Y up, looks down -Z.
    rot = Matrix((right, up, -forward)).transposed()
    obj.matrix_world = Matrix.Translation(pos) @ rot.to_4x4()
    scene.camera = obj
    scene.render.resolution_x = cam["width"]
    scene.render.resolution_y = cam["height"]
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    return {"angle_y_deg": math.degrees(data.angle_y)}


# --- Media ------------------------------------------------------------------------------------
def volume_material(name, medium):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    closures = []
    phase = medium.get("phase", {"type": "isotropic"})
    kind = phase.get("type", "isotropic")
    if kind == "isotropic":
        lobes = [(1.0, 0.0)]
    elif kind == "hg":
        lobes = [(1.0, float(phase["g"]))]
    elif kind == "double_hg":
        w = float(phase["w"])
        lobes = [(w, float(phase["g1"])), (1.0 - w, float(phase["g2"]))]
        if 0.0 < w < 1.0 and not ALLOW_MULTI_LOBE:
            # Measured against single_scatter_reference.py: Cycles 3.4 weighs two added Volume
            # Scatter closures equally in light sampling (2.000x for w = 0.5 or g1 = g2).
            raise ValueError(f"{name}: double_hg needs two Volume Scatter closures, which Cycles 3.4 "
                             "does not weigh correctly (docs/validation/cycles.md); "
                             "--allow-multi-lobe renders it anyway")
    else:
        raise ValueError(f"{name}: phase '{kind}' has no Cycles equivalent")
    color, scale = color_and_scale(medium["sigma_s"])
    for weight, g in lobes:
        if scale * weight <= 0.0:
            continue
        s = nt.nodes.new("ShaderNodeVolumeScatter")
        s.inputs["Color"].default_value = (*color, 1.0)
        s.inputs["Density"].default_value = scale * weight
        s.inputs["Anisotropy"].default_value = g
        closures.append(s.outputs[0])
    acolor, ascale = color_and_scale(medium.get("sigma_a", 0.0))
    if ascale > 0.0:
        a = nt.nodes.new("ShaderNodeVolumeAbsorption")
        a.inputs["Color"].default_value = (*(1.0 - v for v in acolor), 1.0)
        a.inputs["Density"].default_value = ascale
        closures.append(a.outputs[0])
    # Constant emission (radiance per unit length): an Emission closure in the volume, Strength x Color.
    ecolor, escale = color_and_scale(medium.get("emission", 0.0))
    if ecolor and escale > 0.0:
        e = nt.nodes.new("ShaderNodeEmission")
        e.inputs["Color"].default_value = (*ecolor, 1.0)
        e.inputs["Strength"].default_value = escale
        closures.append(e.outputs[0])
    while len(closures) > 1:
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(closures.pop(), add.inputs[1])
        nt.links.new(closures.pop(), add.inputs[0])
        closures.append(add.outputs[0])
    if closures:
        nt.links.new(closures[0], out.inputs["Volume"])
    mat.cycles.homogeneous_volume = True
    return mat


def sphere_mesh(name, radius, segments):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=segments // 2, radius=1.0)
    unit_volume = bm.calc_volume()
    # Scale so that the polyhedron holds the sphere's volume (its vertices lie slightly outside).
    k = (4.0 / 3.0 * math.pi / unit_volume) ** (1.0 / 3.0)
    bmesh.ops.scale(bm, vec=Vector((k * radius,) * 3), verts=bm.verts)
    r = [v.co.length for v in bm.verts]
    info = {"faces": len(bm.faces), "volume_scale": k ** 3,
            "vertex_radius_rel": max(r) / radius - 1.0}
    # Faces are flat: the distance of face centres from the centre bounds the inner deviation.
    info["face_centre_radius_rel"] = min(f.calc_center_median().length for f in bm.faces) / radius - 1.0
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    return mesh, info


def box_mesh(name, lo, hi):
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    for v in bm.verts:
        v.co = Vector(tuple(lo[i] + (v.co[i] + 0.5) * (hi[i] - lo[i]) for i in range(3)))
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    return mesh


def transform_matrix(t):
    """A nimbus `transform` block as a 4x4 Matrix: T R_n ... R_1 S, or the row-major `matrix`."""
    if not t:
        return Matrix.Identity(4)
    if "matrix" in t:
        m = Matrix([[float(v) for v in row] for row in t["matrix"]])
        return m
    sc = t.get("scale", 1.0)
    sc = [float(sc)] * 3 if isinstance(sc, (int, float)) else [float(v) for v in sc]
    m = Matrix.Diagonal(Vector((*sc, 1.0)))
    for r in t.get("rotate", []):
        m = Matrix.Rotation(math.radians(float(r["degrees"])), 4, Vector(r["axis"]).normalized()) @ m
    return Matrix.Translation(Vector(t.get("translate", [0, 0, 0]))) @ m


def rectangle_mesh(name, shape):
    c = Vector(shape.get("center", [0, 0, 0]))
    n = Vector(shape.get("normal", [0, 0, 1])).normalized()
    up = Vector(shape.get("up", [0, 1, 0]))
    up = (up - up.dot(n) * n).normalized()
    right = n.cross(up)
    w, h = (float(v) / 2.0 for v in shape["size"])
    verts = [c - w * right - h * up, c + w * right - h * up, c + w * right + h * up, c - w * right + h * up]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in verts], [], [(0, 1, 2, 3)])
    return mesh


def obj_vertices(path):
    out = []
    with open(path) as f:
        for line in f:
            p = line.split()
            if p and p[0] == "v":
                out.append(tuple(float(x) for x in p[1:4]))
    return np.array(out, dtype=np.float64)


def import_obj(name, path):
    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
    new = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if len(new) != 1:
        raise ValueError(f"{name}: {path}: expected one mesh object from the OBJ importer, got {len(new)}")
    obj = new[0]
    obj.name = name
    # The importer may place the object with a matrix: bake it, then check OBJ coords = world coords.
    obj.data.transform(obj.matrix_world)
    obj.matrix_world = Matrix.Identity(4)
    got = np.array([tuple(v.co) for v in obj.data.vertices], dtype=np.float64)
    want = obj_vertices(path)
    srt = lambda a: a[np.lexsort(a.T[::-1])]  # noqa: E731
    if got.shape != want.shape or not np.allclose(srt(got), srt(want), atol=1e-5):
        raise ValueError(f"{name}: {path}: imported vertices do not match the file's coordinates "
                         f"(bounds {got.min(0)}..{got.max(0)} vs {want.min(0)}..{want.max(0)})")
    obj.data.materials.clear()
    for p in obj.data.polygons:
        p.material_index = 0
    return obj, {"mesh": path, "vertices": len(got), "faces": len(obj.data.polygons)}


def surface_material(name, material):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    kind = material.get("type", "diffuse")
    if kind == "diffuse":
        d = nt.nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Color"].default_value = (*rgb(material.get("albedo", 0.8)), 1.0)
        d.inputs["Roughness"].default_value = 0.0
        nt.links.new(d.outputs[0], out.inputs["Surface"])
    elif kind == "holdout":
        h = nt.nodes.new("ShaderNodeHoldout")
        nt.links.new(h.outputs[0], out.inputs["Surface"])
    else:
        raise ValueError(f"{name}: material '{kind}' has no Cycles equivalent here")
    return mat


def no_terminator_offset(obj):
    for holder in (obj, getattr(obj, "cycles", None)):
        for attr in ("shadow_terminator_offset", "shadow_terminator_geometry_offset",
                     "shadow_terminator_shading_offset"):
            if holder is not None and hasattr(holder, attr):
                setattr(holder, attr, 0.0)


def build_surfaces(surfaces, segments, scene_dir):
    notes = []
    for i, surf in enumerate(surfaces):
        shape = surf["shape"]
        name = f"surface{i}"
        kind = shape["type"]
        placement = Matrix.Identity(4)
        if kind == "sphere":
            mesh, info = sphere_mesh(name, float(shape["radius"]), segments)
            for p in mesh.polygons:
                p.use_smooth = True
            obj = link(bpy.data.objects.new(name, mesh))
            placement = Matrix.Translation(Vector(shape.get("center", [0, 0, 0])))
        elif kind == "rectangle":
            obj = link(bpy.data.objects.new(name, rectangle_mesh(name, shape)))
            info = "4-vertex plane (exact)"
        elif kind == "box":
            obj = link(bpy.data.objects.new(name, box_mesh(name, shape["min"], shape["max"])))
            info = "cube mesh (exact)"
        elif kind == "mesh":
            path = shape["file"]
            if not path.startswith("/"):
                path = str(scene_dir / path)
            obj, info = import_obj(name, path)
        else:
            raise ValueError(f"{name}: surface shape '{kind}' is not supported")
        obj.matrix_world = transform_matrix(surf.get("transform")) @ placement
        obj.data.materials.append(surface_material(name, surf.get("material", {"type": "diffuse"})))
        no_terminator_offset(obj)
        notes.append({name: info})
    return notes


def build_media(media, segments):
    notes = []
    for i, medium in enumerate(media):
        shape = medium["shape"]
        name = f"medium{i}"
        placement = Matrix.Identity(4)
        if shape["type"] == "sphere":
            mesh, info = sphere_mesh(name, float(shape["radius"]), segments)
            obj = link(bpy.data.objects.new(name, mesh))
            placement = Matrix.Translation(Vector(shape.get("center", [0, 0, 0])))
            notes.append({name: info})
        elif shape["type"] == "box":
            obj = link(bpy.data.objects.new(name, box_mesh(name, shape["min"], shape["max"])))
            notes.append({name: "cube mesh (exact)"})
        else:
            raise ValueError(f"{name}: shape '{shape['type']}' is not supported (homogeneous sphere/box only)")
        obj.matrix_world = transform_matrix(medium.get("transform")) @ placement
        obj.data.materials.append(volume_material(name, medium))
    return notes


# --- Lights -----------------------------------------------------------------------------------
def environment_image(world, bg, light, scene_dir):
    """An environment image light: Texture Coordinate (Generated) -> Mapping (R^-1) -> Environment
    Texture -> Background, Strength = intensity."""
    nodes, links = world.node_tree.nodes, world.node_tree.links
    path = Path(light["file"])
    path = path if path.is_absolute() else scene_dir / path
    tex = nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(str(path))
    tex.image.colorspace_settings.name = "Linear"
    tex.interpolation = "Closest"
    tex.projection = "EQUIRECTANGULAR"
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.vector_type = "POINT"
    mapping.inputs["Rotation"].default_value = transform_matrix(light.get("transform")).to_3x3().inverted().to_euler("XYZ")
    links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = float(light.get("intensity", 1.0))


def build_lights(lights, scene_dir, sphere_lights="mesh", segments=256):
    scene = bpy.context.scene
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bg.inputs["Strength"].default_value = 0.0
    scene.world = world
    for i, light in enumerate(lights):
        kind = light["type"]
        if kind == "directional":
            color, scale = color_and_scale(light["irradiance"])
            data = bpy.data.lights.new(f"sun{i}", "SUN")
            data.energy = scale  # W/m^2 on a plane facing the sun
            data.color = color
            data.angle = math.radians(light.get("angular_diameter_deg", 0.0))
            obj = link(bpy.data.objects.new(f"sun{i}", data))
            # Sun lamps shine down their local -Z: point local +Z against the travel direction.
            obj.rotation_euler = (-Vector(light["direction"]).normalized()).to_track_quat("Z", "Y").to_euler()
        elif kind == "point":
            color, scale = color_and_scale(light["intensity"])
            data = bpy.data.lights.new(f"point{i}", "POINT")
            data.energy = 4.0 * math.pi * scale  # Cycles: intensity = power / (4 pi) W/sr
            data.color = color
            data.shadow_soft_size = 0.0
            obj = link(bpy.data.objects.new(f"point{i}", data))
            obj.location = Vector(light["position"])
        elif kind == "environment" and "file" in light:
            environment_image(world, bg, light, scene_dir)
        elif kind == "sphere" and sphere_lights == "mesh":
            build_sphere_light_mesh(i, light, segments)
        elif kind in ("spot", "sphere", "rectangle"):
            build_area_or_spot_light(i, light)
        elif kind == "environment":
            bg.inputs["Color"].default_value = (*rgb(light["radiance"]), 1.0)
            bg.inputs["Strength"].default_value = 1.0
        else:
            raise ValueError(f"light {i}: type '{kind}' is not supported")


def spot_without_cosine(data, axis):
    """A light node tree dividing the emission by the cosine to the spot's axis, which Cycles 3.4 applies
    on top of the smoothstep edge (spot_light_attenuation: attenuation = dot(dir, N) * smoothstep(...)).
    In a lamp's shader the Geometry Normal is the lamp's Ng = the direction from the lamp to the shaded
    point (kernel/light/light.h: ls->Ng = -ls->D)."""
    data.use_nodes = True
    nt = data.node_tree
    emission = nt.nodes["Emission"]
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    dot = nt.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    dot.inputs[1].default_value = tuple(axis)
    clamp = nt.nodes.new("ShaderNodeMath")
    clamp.operation = "MAXIMUM"
    clamp.inputs[1].default_value = 1e-4
    inverse = nt.nodes.new("ShaderNodeMath")
    inverse.operation = "DIVIDE"
    inverse.inputs[0].default_value = 1.0
    nt.links.new(geometry.outputs["Normal"], dot.inputs[0])
    nt.links.new(dot.outputs["Value"], clamp.inputs[0])
    nt.links.new(clamp.outputs["Value"], inverse.inputs[1])
    nt.links.new(inverse.outputs["Value"], emission.inputs["Strength"])


def build_sphere_light_mesh(i, light, segments):
    """A sphere light as a UV sphere (equal volume) whose front faces emit `radiance` (Emission strength 1
    = radiance 1) and which every ray passes through (Transparent BSDF), like nimbus' sphere light: it
    emits outward only and occludes nothing. Seen by the camera only if `visible`."""
    T = transform_matrix(light.get("transform"))
    r = light["radius"] * T.to_3x3().col[0].length
    L = rgb(light["radiance"]) if "radiance" in light else \
        tuple(p / (4.0 * math.pi ** 2 * r * r) for p in rgb(light["power"]))
    mesh, _ = sphere_mesh(f"sphere_light{i}", r, segments)
    obj = link(bpy.data.objects.new(f"sphere_light{i}", mesh))
    obj.location = T @ Vector(light["center"])
    for poly in mesh.polygons:
        poly.use_smooth = True
    mat = bpy.data.materials.new(f"sphere_light{i}")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emission = nt.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*L, 1.0)
    emission.inputs["Strength"].default_value = 1.0
    through = nt.nodes.new("ShaderNodeBsdfTransparent")
    through2 = nt.nodes.new("ShaderNodeBsdfTransparent")
    add = nt.nodes.new("ShaderNodeAddShader")
    mix = nt.nodes.new("ShaderNodeMixShader")
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    nt.links.new(emission.outputs[0], add.inputs[0])
    nt.links.new(through.outputs[0], add.inputs[1])
    nt.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(add.outputs[0], mix.inputs[1])  # front faces: emission + transparent
    nt.links.new(through2.outputs[0], mix.inputs[2])  # back faces: transparent
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    mesh.materials.append(mat)
    obj.visible_camera = bool(light.get("visible", False))
    obj.visible_shadow = True


def build_area_or_spot_light(i, light):
    """spot: SPOT lamp, radius 0, Power = 4 pi I, spot_size = cone angle, spot_blend = blend, the cosine
    factor divided out (spot_without_cosine). sphere: POINT lamp of radius r, Power = 4 pi^2 r^2 L
    (Cycles: L = P / (4 pi) / (pi r^2)), which Cycles 3.4 samples as a disc facing the shaded point.
    rectangle: AREA lamp (RECTANGLE, size x = width along normal x up, y = height along up), emitting
    along its local -Z; Power = 4 A L (Cycles 3.4: L = P / (4 A), kernel/light/light.h eval_fac = 1/4
    invarea; checked in docs/validation/cycles.md). visible -> the object's camera visibility."""
    kind = light["type"]
    T = transform_matrix(light.get("transform"))
    if kind == "spot":
        color, scale = color_and_scale(light["intensity"])
        data = bpy.data.lights.new(f"spot{i}", "SPOT")
        data.energy = 4.0 * math.pi * scale
        data.spot_size = math.radians(light["cone_angle_deg"])
        data.spot_blend = light.get("blend", 0.0)
        data.shadow_soft_size = 0.0
        axis = (T.to_3x3() @ Vector(light["direction"])).normalized()
        spot_without_cosine(data, axis)
        obj = link(bpy.data.objects.new(f"spot{i}", data))
        obj.location = T @ Vector(light["position"])
        obj.rotation_euler = axis.to_track_quat("-Z", "Y").to_euler()  # spots shine down local -Z
        data.color = color
        return
    color, scale = color_and_scale(light["radiance"]) if "radiance" in light else (None, None)
    if kind == "sphere":
        r = light["radius"] * T.to_3x3().col[0].length
        if scale is None:
            color, scale = color_and_scale([p / (4.0 * math.pi ** 2 * r * r) for p in rgb(light["power"])])
        data = bpy.data.lights.new(f"sphere{i}", "POINT")
        data.shadow_soft_size = r
        data.energy = 4.0 * math.pi ** 2 * r * r * scale
        obj = link(bpy.data.objects.new(f"sphere{i}", data))
        obj.location = T @ Vector(light["center"])
    else:
        s = T.to_3x3().col[0].length
        w, h = light["size"][0] * s, light["size"][1] * s
        if scale is None:
            color, scale = color_and_scale([p / (math.pi * w * h) for p in rgb(light["power"])])
        n = (T.to_3x3() @ Vector(light["normal"])).normalized()
        up = T.to_3x3() @ Vector(light.get("up", [0, 1, 0]))
        up = (up - n * up.dot(n)).normalized()
        data = bpy.data.lights.new(f"rect{i}", "AREA")
        data.shape = "RECTANGLE"
        data.size, data.size_y = w, h
        data.energy = 4.0 * w * h * scale
        obj = link(bpy.data.objects.new(f"rect{i}", data))
        # Local -Z = normal, local +Y = up, so local +X = up x (-normal) = normal x up (nimbus' width axis).
        obj.matrix_world = Matrix.Translation(T @ Vector(light["center"])) @ \
            Matrix((n.cross(up), up, -n)).transposed().to_4x4()
    data.color = color
    obj.visible_camera = bool(light.get("visible", False))


# --- Render settings --------------------------------------------------------------------------
def configure(args, integrator):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = args.samples or int(integrator.get("spp", 64))
    c.seed = args.seed if args.seed is not None else int(integrator.get("seed", 1))
    c.use_animated_seed = False
    c.sample_offset = 0
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_preview_denoising = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0  # Blender's default is 10: it would clip bright paths
    c.light_sampling_threshold = 0.0  # default 0.01 culls dim lights: biased
    max_events = int(integrator.get("max_events", 0))
    c.max_bounces = 1024
    c.volume_bounces = 1024 if max_events == 0 else max_events - 1
    c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 1024
    c.transparent_max_bounces = 1024
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.film_exposure = 1.0
    c.scrambling_distance = 1.0
    c.auto_scrambling_distance = False
    c.use_fast_gi = False
    scene.render.threads_mode = "FIXED"
    scene.render.threads = args.threads
    scene.render.film_transparent = False
    scene.render.use_motion_blur = False
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.render.dither_intensity = 0.0
    vs = scene.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    vs.use_curve_mapping = False
    im = scene.render.image_settings
    im.file_format = "OPEN_EXR"
    im.color_mode = "RGB"
    im.color_depth = "32"
    im.exr_codec = "ZIP"


def exr_to_array(path):
    """Pixels of an EXR as (h, w, 3) float32, row 0 = top."""
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    return buf.reshape(h, w, 4)[::-1, :, :3].copy()


def main():
    global ALLOW_MULTI_LOBE
    args = parse_args()
    ALLOW_MULTI_LOBE = args.allow_multi_lobe
    with open(args.scene) as f:
        scene_json = json.load(f)
    if scene_json.get("film", {}).get("transparent", False):
        raise ValueError("film.transparent: only the opaque film (RGB compared) is supported")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    cam_info = build_camera(scene_json["camera"])
    mesh_info = build_media(scene_json.get("media", []), args.sphere_segments)
    mesh_info += build_surfaces(scene_json.get("surfaces", []), args.sphere_segments,
                                Path(args.scene).resolve().parent)
    build_lights(scene_json.get("lights", []), Path(args.scene).resolve().parent, args.sphere_lights,
                 args.sphere_segments)
    configure(args, scene_json.get("integrator", {}))
    print("scene_to_blender:", json.dumps({"camera": cam_info, "media": mesh_info,
                                           "samples": bpy.context.scene.cycles.samples,
                                           "seed": bpy.context.scene.cycles.seed,
                                           "volume_bounces": bpy.context.scene.cycles.volume_bounces}))
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=args.blend)
    bpy.context.scene.render.filepath = args.output
    bpy.ops.render.render(write_still=True)
    if args.npy:
        np.save(args.npy, exr_to_array(args.output))


if __name__ == "__main__":
    main()
