#!/usr/bin/env python3
"""Writes the glTF and PLY test files of tests/data/models and tests/data/bad_models.

models/scene.gltf (buffer in a data: URI) and models/scene.glb (the same scene, buffer in the
binary chunk): one triangle placed by four nodes with four materials, a perspective camera and
two point lights; tests/model_loader_test.cpp says what each holds and checks it. models/quad.ply:
a quad with red vertex colours. bad_models/: a truncated .glb, a .gltf with broken JSON, a missing
buffer, a buffer that is /dev/zero, files whose first bytes do not match their extension, and
PLY files with a bad header, no faces, an index out of range or no face list.

Usage: scripts/make-test-models.py   (standard library only; run from anywhere)
"""
import base64
import json
import os
import struct

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests', 'data')
pos = struct.pack('<9f', 0,0,0, 1,0,0, 0,1,0)
idx = struct.pack('<3H', 0, 1, 2) + b'\0\0'
buf = pos + idx
def gltf(buffer_uri):
    mesh = lambda m: {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": m}]}
    return {
        "asset": {"version": "2.0", "generator": "rtlab tests"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 3, 4, 5, 6, 7]}],
        "nodes": [
            {"name": "red", "mesh": 0, "translation": [2, 0, 0], "scale": [2, 2, 2]},
            {"name": "group", "translation": [0, 0, 5], "rotation": [0, 0.7071067811865476, 0, 0.7071067811865476], "children": [2]},
            {"name": "mirror", "mesh": 1, "translation": [1, 0, 0]},
            {"name": "eye", "camera": 0, "translation": [0, 1, -10], "rotation": [0, 1, 0, 0]},
            {"name": "lamp", "translation": [0, 10, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "fill", "translation": [3, 3, 3], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "blend", "mesh": 2, "translation": [0, 0, 10]},
            {"name": "glass", "mesh": 3, "translation": [0, 0, 12]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"aspectRatio": 2.0, "yfov": 0.5, "znear": 0.1, "zfar": 100}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20},
            {"type": "point", "color": [1, 1, 1], "intensity": 5}]}},
        "materials": [
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 0.5}, "emissiveFactor": [0.1, 0, 0]},
            {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 1, "roughnessFactor": 0}},
            {"name": "blend", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 0.25], "metallicFactor": 0, "roughnessFactor": 1}, "alphaMode": "BLEND"},
            {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0}, "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}},
        ],
        "meshes": [mesh(0), mesh(1), mesh(2), mesh(3)],
        "buffers": [{"byteLength": len(buf), **({"uri": buffer_uri} if buffer_uri is not None else {})}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6, "target": 34963}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    }
def dump(obj): return json.dumps(obj, indent=1)
open(f'{root}/models/scene.gltf', 'w').write(dump(gltf('data:application/octet-stream;base64,' + base64.b64encode(buf).decode())) + '\n')
# GLB: the same scene with the buffer in the binary chunk
j = json.dumps(gltf(None)).encode()
j += b' ' * (-len(j) % 4)
b = buf + b'\0' * (-len(buf) % 4)
glb = struct.pack('<4sII', b'glTF', 2, 12 + 8 + len(j) + 8 + len(b)) + struct.pack('<I4s', len(j), b'JSON') + j + struct.pack('<I4s', len(b), b'BIN\0') + b
open(f'{root}/models/scene.glb', 'wb').write(glb)
open(f'{root}/bad_models/truncated.glb', 'wb').write(glb[:len(glb) // 2])
text = dump(gltf('data:application/octet-stream;base64,' + base64.b64encode(buf).decode()))
open(f'{root}/bad_models/broken_json.gltf', 'w').write(text[:200] + '\n')
open(f'{root}/bad_models/missing_buffer.gltf', 'w').write(dump(gltf('nothere.bin')) + '\n')
open(f'{root}/bad_models/buffer_is_a_device.gltf', 'w').write(dump(gltf('../../../../../../../../../dev/zero')) + '\n')
open(f'{root}/bad_models/not_gltf.glb', 'w').write('{"asset": {"version": "2.0"}}\n')
open(f'{root}/bad_models/not_json.gltf', 'w').write('glTF binary?\n')
open(f'{root}/models/quad.ply', 'w').write('''ply
format ascii 1.0
comment a unit quad in the z = 0 plane, red vertices: two triangles of material "default #FF0000"
element vertex 4
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
element face 1
property list uchar int vertex_indices
end_header
0 0 0 255 0 0
1 0 0 255 0 0
1 1 0 255 0 0
0 1 0 255 0 0
4 0 1 2 3
''')
open(f'{root}/bad_models/bad_header.ply', 'w').write('''ply
format ascii 1.0
element vertex three
property float x
property float y
property float z
end_header
0 0 0
1 0 0
0 1 0
''')
open(f'{root}/bad_models/points.ply', 'w').write('''ply
format ascii 1.0
element vertex 3
property float x
property float y
property float z
end_header
0 0 0
1 0 0
0 1 0
''')
open(f'{root}/bad_models/index_out_of_range.ply', 'w').write('''ply
format ascii 1.0
element vertex 3
property float x
property float y
property float z
element face 1
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
0 1 0
3 0 1 7
''')
open(f'{root}/bad_models/not_ply.ply', 'w').write('solid cube\nendsolid\n')
open(f'{root}/bad_models/truncated.ply', 'w').write('''ply
format ascii 1.0
comment the header promises 2 faces, the file ends after the vertices
element vertex 3
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
0 1 0
''')
open(f'{root}/bad_models/empty.ply', 'w').write('')
