"""Writes the meshes of the test arm (this project's own files, no third-party data).

usage: python3 make_meshes.py   (from this folder; the files are committed, rerun only to change them)

meshes/base.stl   binary STL, millimetres (the URDF scales it by 0.001): the pedestal
meshes/link1.stl  ASCII STL, metres: the column of link_1
meshes/link2.dae  Collada, centimetres (<unit meter="0.01">), Z up, placed by a node <matrix>
meshes/link3.obj  OBJ, metres, along z (the URDF turns it onto x with its visual rpy)
"""
import struct

def box(lo, hi):
    """The 12 triangles of an axis-aligned box, outward (counter-clockwise seen from outside)."""
    c = lambda i: (hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return [(c(f[0]), c(f[1]), c(f[2])) for f in faces] + [(c(f[0]), c(f[2]), c(f[3])) for f in faces]

def binary_stl(path, tris):
    with open(path, "wb") as f:
        f.write(b"ofmpc test arm: base (mm)".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<3f", 0, 0, 0))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(b"\0\0")

def ascii_stl(path, tris):
    with open(path, "w") as f:
        f.write("solid link1\n")
        for t in tris:
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for v in t:
                f.write("      vertex %g %g %g\n" % v)
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid link1\n")

def dae(path, tris):
    pos = [v for t in tris for v in t]
    floats = " ".join("%g %g %g" % v for v in pos)
    idx = " ".join(str(i) for i in range(len(pos)))
    with open(path, "w") as f:
        f.write(f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="arm" name="arm"><mesh>
      <source id="arm-pos"><float_array id="arm-pos-array" count="{3 * len(pos)}">{floats}</float_array>
        <technique_common><accessor source="#arm-pos-array" count="{len(pos)}" stride="3"/></technique_common></source>
      <vertices id="arm-v"><input semantic="POSITION" source="#arm-pos"/></vertices>
      <triangles count="{len(tris)}"><input semantic="VERTEX" source="#arm-v" offset="0"/><p>{idx}</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="Scene">
    <node id="arm"><matrix>1 0 0 0  0 1 0 0  0 0 1 18  0 0 0 1</matrix><instance_geometry url="#arm"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
""")

def obj(path, tris):
    with open(path, "w") as f:
        f.write("# ofmpc test arm: link_3 along z\n")
        for t in tris:
            for v in t:
                f.write("v %g %g %g\n" % v)
        for i in range(len(tris)):
            f.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))

binary_stl("meshes/base.stl", box((-150, -150, 0), (150, 150, 200)))
ascii_stl("meshes/link1.stl", box((-0.08, -0.08, 0.2), (0.12, 0.08, 0.40)))
dae("meshes/link2.dae", box((-6, -9, -18), (6, -3, 18)))
obj("meshes/link3.obj", box((-0.05, -0.05, -0.03), (0.05, 0.05, 0.24)))
