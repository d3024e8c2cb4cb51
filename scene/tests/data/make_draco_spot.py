"""Writes spot-draco.glb: Spot (positions, normals, UVs) compressed with Google's C++
Draco encoder (through the DracoPy package) inside a KHR_draco_mesh_compression glTF,
and spot-draco.json: what that encoder's own decoder reads back from the stream (point
and face counts, and sums of each attribute), for the loader's test to compare against.

    pip install DracoPy numpy && python3 make_draco_spot.py ../../../assets/meshes/spot.obj
"""
import json
import struct
import sys

import DracoPy
import numpy as np

obj = sys.argv[1]
v, vt, vn, corners = [], [], [], []
for line in open(obj):
    f = line.split()
    if not f:
        continue
    if f[0] == "v":
        v.append([float(x) for x in f[1:4]])
    elif f[0] == "vt":
        vt.append([float(x) for x in f[1:3]])
    elif f[0] == "vn":
        vn.append([float(x) for x in f[1:4]])
    elif f[0] == "f":
        corners.extend(tuple(int(i) - 1 for i in c.split("/")) for c in f[1:4])

# One vertex per distinct (position, uv) pair; Spot's OBJ has no normals, so each vertex
# gets the normalised sum of its position's face normals.
pos = np.array(v, dtype=np.float64)
normal = np.zeros_like(pos)
for t in range(0, len(corners), 3):
    a, b, c = (corners[t + k][0] for k in range(3))
    n = np.cross(pos[b] - pos[a], pos[c] - pos[a])
    for i in (a, b, c):
        normal[i] += n
normal /= np.linalg.norm(normal, axis=1, keepdims=True)
ids, faces, points, uvs, normals = {}, [], [], [], []
for c in corners:
    key = (c[0], c[1])
    if key not in ids:
        ids[key] = len(points)
        points.append(pos[c[0]])
        uvs.append(vt[c[1]])
        normals.append(normal[c[0]])
    faces.append(ids[key])
points = np.array(points, dtype=np.float32)
uvs = np.array(uvs, dtype=np.float64)
normals = np.array(normals, dtype=np.float64)
faces = np.array(faces, dtype=np.uint32).reshape(-1, 3)

drc = DracoPy.encode(
    points, faces, quantization_bits=14, compression_level=7,
    tex_coord=uvs, tex_coord_quantization_bits=12,
    normals=normals, normal_quantization_bits=10,
)
back = DracoPy.decode(drc)
got_points = np.asarray(back.points, dtype=np.float64)
got_faces = np.asarray(back.faces)
expected = {
    "points": int(len(got_points)),
    "faces": int(len(got_faces)),
    "position_sum": got_points.sum(axis=0).tolist(),
    "uv_sum": np.asarray(back.tex_coord, dtype=np.float64).sum(axis=0).tolist(),
    "normal_sum": np.asarray(back.normals, dtype=np.float64).sum(axis=0).tolist(),
    # Sum over faces of each corner's position: ties faces to points.
    "corner_position_sum": got_points[got_faces.reshape(-1)].sum(axis=0).tolist(),
    "min": got_points.min(axis=0).tolist(),
    "max": got_points.max(axis=0).tolist(),
}

# DracoPy 2.2.0 gives texture coordinates, normals and positions the unique ids 0, 1
# and 2 (as the stream's attribute headers say).
n, count = expected["points"], 3 * expected["faces"]
doc = {
    "asset": {"version": "2.0", "generator": "make_draco_spot.py (DracoPy 2.2.0)"},
    "extensionsUsed": ["KHR_draco_mesh_compression"],
    "extensionsRequired": ["KHR_draco_mesh_compression"],
    "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "spot"}],
    "meshes": [{"name": "spot", "primitives": [{
        "attributes": {"POSITION": 0, "TEXCOORD_0": 1, "NORMAL": 2}, "indices": 3,
        "extensions": {"KHR_draco_mesh_compression": {
            "bufferView": 0, "attributes": {"POSITION": 2, "TEXCOORD_0": 0, "NORMAL": 1}}},
    }]}],
    "buffers": [{"byteLength": len(drc)}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(drc)}],
    "accessors": [
        {"componentType": 5126, "count": n, "type": "VEC3",
         "min": expected["min"], "max": expected["max"]},
        {"componentType": 5126, "count": n, "type": "VEC2"},
        {"componentType": 5126, "count": n, "type": "VEC3"},
        {"componentType": 5125, "count": count, "type": "SCALAR"},
    ],
}
text = json.dumps(doc, separators=(",", ":")).encode()
text += b" " * (-len(text) % 4)
bin_ = drc + b"\0" * (-len(drc) % 4)
glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(bin_))
glb += struct.pack("<I4s", len(text), b"JSON") + text
glb += struct.pack("<I4s", len(bin_), b"BIN\0") + bin_
open("spot-draco.glb", "wb").write(glb)
json.dump(expected, open("spot-draco.json", "w"), indent=1)
print(n, "points,", expected["faces"], "faces,", len(drc), "bytes of Draco")
