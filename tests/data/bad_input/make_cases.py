#!/usr/bin/env python3
"""Writes the bad-input corpus (tests/data/bad_input/): one file per case, named for what is
wrong, each with a sidecar <case>.expect (see README.md). Run from anywhere; it rewrites the
generated cases in place (hand-written cases are not touched)."""
import copy
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))

GOOD_SCENE = {
    "format": "penumbra/scene@1",
    "name": "bad-input-base",
    "camera": {"position": [0, 1.2, 3.0], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
               "fov_y_deg": 40, "width": 32, "height": 24},
    "materials": {"white": {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}},
    "shapes": [{"type": "quad", "origin": [-2, 0, 2], "edge1": [4, 0, 0], "edge2": [0, 0, -4],
                "material": "white"}],
    "lights": [{"type": "quad", "origin": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0],
                "edge2": [0, 0, 1], "radiance": [5, 5, 5]}],
}


def write(folder, name, text, expect):
    os.makedirs(os.path.join(HERE, folder), exist_ok=True)
    with open(os.path.join(HERE, folder, name), "w") as f:
        f.write(text)
    with open(os.path.join(HERE, folder, name + ".expect"), "w") as f:
        for line in expect:
            f.write(line + "\n")


def scene_with(change):
    scene = copy.deepcopy(GOOD_SCENE)
    change(scene)
    return json.dumps(scene, indent=1)


def setter(path, value):
    def change(scene):
        node = scene
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return change


def deleter(path):
    def change(scene):
        node = scene
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return change


def scene_case(name, change_or_text, message, status="INVALID_ARGUMENT", extra=(), why=""):
    text = change_or_text if isinstance(change_or_text, str) else scene_with(change_or_text)
    write("scenes", name + ".json", text,
          ["# " + why, "status: " + status, "message: " + message] + list(extra))


good = json.dumps(GOOD_SCENE, indent=1)
os.makedirs(os.path.join(HERE, "good"), exist_ok=True)
with open(os.path.join(HERE, "good", "base.json"), "w") as f:
    f.write(good + "\n")  # the scene every case departs from; it renders

# Syntax.
scene_case("truncated-json", good[: len(good) // 2], "invalid JSON",
           why="the file ends in the middle of the camera")
scene_case("empty-file", "", "invalid JSON", why="zero bytes")
scene_case("not-an-object", "[1, 2, 3]", "$: expected an object",
           why="the document is an array")
scene_case("trailing-garbage", good + "\n}}", "invalid JSON", why="bytes after the document")
scene_case("deep-nesting-10000", '{"format": "penumbra/scene@1", "camera": ' + "[" * 10000 +
           "]" * 10000 + "}", "JSON nesting deeper than 64 levels",
           why="10,000 nested arrays (a stack-exhaustion attempt)")
scene_case("wrong-format", setter(["format"], "penumbra/probe@1"), "$.format: not a scene",
           why="another format")
scene_case("future-format-version", setter(["format"], "penumbra/scene@9"),
           "unsupported scene format version", why="a version this reader does not read")
scene_case("missing-camera", deleter(["camera"]), "$.camera: missing required key 'camera'",
           why="no camera")
scene_case("misspelled-lights", lambda s: s.update({"lihgts": s.pop("lights")}),
           "(found 'lihgts': misspelled?)", why="a misspelled required key")

# Wrong types.
scene_case("width-is-string", setter(["camera", "width"], "512"),
           "$.camera.width: expected a number, got string", why="a number written as a string")
scene_case("width-is-fraction", setter(["camera", "width"], 32.5),
           "$.camera.width: expected an integer", why="a fractional pixel count")
scene_case("radiance-two-components", setter(["lights", 0, "radiance"], [5, -5]),
           "$.lights[0].radiance: expected an array of 3 numbers",
           why="an RGB value with two components")
scene_case("materials-is-array", setter(["materials"], [{"type": "lambert"}]),
           "$.materials: expected an object, got array", why="materials as a list")
scene_case("shape-is-number", setter(["shapes"], [7]), "$.shapes[0]: expected an object",
           why="a shape that is a number")
scene_case("position-null", setter(["camera", "position"], None),
           "$.camera.position: expected an array of 3 numbers", why="null where a point belongs")
scene_case("albedo-is-true", setter(["materials", "white", "albedo"], True),
           "$.materials.white.albedo", why="a boolean colour")

# NaN and infinity, as JSON can carry them.
scene_case("coordinate-1e999", good.replace('"position": [\n   0,', '"position": [\n   1e999,'),
           "invalid JSON: [json.exception.out_of_range.406] number overflow parsing '1e999'",
           why="1e999 overflows a double (the parser refuses it)")
scene_case("coordinate-nan-literal", good.replace('"fov_y_deg": 40', '"fov_y_deg": NaN'),
           "invalid JSON", why="NaN is not JSON")
scene_case("coordinate-infinity-literal",
           good.replace('"fov_y_deg": 40', '"fov_y_deg": Infinity'), "invalid JSON",
           why="Infinity is not JSON")
scene_case("fov-nan-string", setter(["camera", "fov_y_deg"], "NaN"),
           "$.camera.fov_y_deg: expected a number, got string", why="NaN smuggled as a string")
scene_case("radiance-1e308-squared", setter(["lights", 0, "radiance"], [1e308, 1e308, 1e308]),
           "$.lights[0].radiance: radiance [1e+308,1e+308,1e+308] exceeds the limit max_radiance", why="a finite radiance whose products overflow")
scene_case("coordinate-past-limit", setter(["camera", "position"], [0, 1e300, 3]),
           "exceeds the limit max_coordinate", why="an absurd coordinate")

# Huge counts and resolutions.
scene_case("resolution-huge", setter(["camera", "width"], 1000000),
           "$.camera.width: image size 1000000 exceeds the limit max_resolution",
           why="a million pixels wide")
scene_case("resolution-int-overflow", setter(["camera", "height"], 4294967297),
           "$.camera.height: image size 4294967297 exceeds the limit max_resolution",
           why="a height that wraps a 32-bit int to 1")
scene_case("resolution-negative", setter(["camera", "width"], -64),
           "$.camera.width: image size must be at least 1", why="a negative width")
scene_case("resolution-zero", setter(["camera", "height"], 0),
           "$.camera.height: image size must be at least 1", why="zero height")
scene_case("sphere-subdivisions-huge",
           setter(["shapes"], [{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.3,
                                "subdivisions": 40, "material": "white"}]),
           "$.shapes[0].subdivisions: subdivisions 40 exceeds the limit",
           why="2^80 triangles asked for")
scene_case("polygon-vertices-huge",
           setter(["lights", 0], {"type": "polygon", "radiance": [1, 1, 1],
                                  "vertices": [[i * 1e-3, 1.5, 0] for i in range(2000)]}),
           "more than the limit max_polygon_vertices", why="a 2000-gon")
scene_case("index-out-of-range",
           setter(["shapes"], [{"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                                "indices": [0, 1, 4294967296], "material": "white"}]),
           "$.shapes[0].indices[2]: index 4294967296 out of range", why="an index past the vertices")
scene_case("region-outside-image", setter(["regions"], {"edge": [0, 0, 64, 8]}),
           "$.regions.edge: region [0,0,64,8] lies outside the image", why="past the right edge")

# Degenerate geometry and negative values.
scene_case("negative-radiance", setter(["lights", 0, "radiance"], [5, -1, 5]),
           "$.lights[0].radiance: negative radiance", why="negative emission")
scene_case("zero-area-light", setter(["lights", 0, "edge2"], [2, 0, 0]),
           "$.lights[0]: degenerate quad light", why="edges parallel: zero area")
scene_case("look-at-equals-position", setter(["camera", "look_at"], [0, 1.2, 3.0]),
           "$.camera.look_at: look_at coincides with position", why="no view direction")
scene_case("no-lights", setter(["lights"], []), "$.lights: a scene needs at least one light",
           why="nothing emits")
scene_case("unknown-material", setter(["shapes", 0, "material"], "chrome"),
           "$.shapes[0].material: unknown material 'chrome'", why="undefined material")
scene_case("roughness-zero", setter(["materials", "white"],
                                    {"type": "ggx", "specular": [0.04, 0.04, 0.04],
                                     "roughness": 0}),
           "$.materials.white.roughness: roughness (GGX alpha) must lie in (0, 1]",
           why="a perfect mirror")

# OBJ files: paths that leave the scene's folder, missing and broken files.
obj_shape = lambda path: setter(["shapes"], [{"type": "obj", "file": path, "material": "white"}])
scene_case("obj-path-parent", obj_shape("../outside/plate.obj"),
           "$.shapes[0].file: refused OBJ path: path '../outside/plate.obj' leaves the scene's folder",
           extra=["file: ../outside/plate.obj = ../outside/plate.obj"],
           why="'../' out of the folder (the package even carries the file under that name)")
scene_case("obj-path-deep-parent", obj_shape("meshes/../../outside/plate.obj"),
           "leaves the scene's folder", extra=["file: meshes/part.obj = meshes/part.obj"],
           why="climbs out after a folder")
scene_case("obj-path-absolute", obj_shape("/etc/passwd"),
           "$.shapes[0].file: refused OBJ path: absolute path '/etc/passwd'",
           why="an absolute path")
scene_case("obj-path-backslash", obj_shape("..\\outside\\plate.obj"),
           "contains a backslash", why="a Windows-style escape")
scene_case("obj-symlink-escape", obj_shape("meshes/escape.obj"),
           "outside the scene's folder",
           extra=["wire: none",
                  "# meshes/escape.obj is a symlink to ../../outside/plate.obj: the CLI and the",
                  "# client's packer resolve it and refuse; a package carries bytes, not links"],
           why="a symlink out of the folder")
scene_case("obj-missing", obj_shape("meshes/nowhere.obj"),
           "$.shapes[0].file: OBJ file cannot be read",
           why="the file is neither on disk nor in the package")
scene_case("obj-nan-vertex", obj_shape("meshes/nan-vertex.obj"),
           "is not a finite number", extra=["file: meshes/nan-vertex.obj = meshes/nan-vertex.obj"],
           why="an OBJ vertex 'nan'")
scene_case("obj-index-out-of-range", obj_shape("meshes/bad-index.obj"),
           "vertex index out of range", extra=["file: meshes/bad-index.obj = meshes/bad-index.obj"],
           why="a face naming vertex 9 of 3")
scene_case("obj-no-triangles", obj_shape("meshes/no-faces.obj"),
           "OBJ file has no triangles", extra=["file: meshes/no-faces.obj = meshes/no-faces.obj"],
           why="vertices only")

# pbrt-v3 scenes: every message starts with file:line:column.
PBRT_LIGHT = ('AttributeBegin\nAreaLightSource "diffuse" "rgb L" [4 4 4]\n'
              'Shape "quad" "point o" [0 2 0] "vector u" [1 0 0] "vector v" [0 0 1]\nAttributeEnd\n')


def pbrt_case(name, body, message, extra=(), why="", world=True):
    text = ("WorldBegin\n" + body + PBRT_LIGHT + "WorldEnd\n") if world else body
    write("scenes", name + ".pbrt", text,
          ["# " + why, "status: INVALID_ARGUMENT", "message: " + message] + list(extra))


pbrt_case("pbrt-newline-in-string", 'Film "image\nWorldBegin\n',
          "pbrt-newline-in-string.pbrt:1:12: newline in a string", world=False,
          why="a string left open at the end of its line")
pbrt_case("pbrt-unknown-statement", 'Sphere "x"\n',
          "pbrt-unknown-statement.pbrt:2:1: unknown statement 'Sphere'", why="no such statement")
pbrt_case("pbrt-malformed-number", "Translate 1 2 3.4.5\n",
          "pbrt-malformed-number.pbrt:2:15: malformed number '3.4.5'", why="two decimal points")
pbrt_case("pbrt-number-1e999", "Scale 1e999 1 1\n",
          "pbrt-number-1e999.pbrt:2:7: number 1e999 is out of range", why="overflows a double")
pbrt_case("pbrt-nan-word", "Translate nan 0 0\n",
          "pbrt-nan-word.pbrt:2:11: Translate needs a number, found 'nan'",
          why="NaN written as a word")
pbrt_case("pbrt-index-out-of-range",
          'Shape "trianglemesh" "point P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 5]\n',
          'pbrt-index-out-of-range.pbrt:2:52: Shape "trianglemesh": "integer indices": index 5 '
          'out of range [0, 3)', why="an index past the vertices")
pbrt_case("pbrt-unterminated-array", 'Shape "trianglemesh" "point P" [0 0 0 1 0 0 0 1 0\n',
          "pbrt-unterminated-array.pbrt:1:32: unterminated '[' (no closing ']')", world=False,
          why="the file ends inside an array")
pbrt_case("pbrt-ply-parent-path", 'Shape "plymesh" "string filename" "../outside/plate.ply"\n',
          "refused PLY path: path '../outside/plate.ply' leaves the scene's folder",
          why="a PLY path out of the scene's folder")
pbrt_case("pbrt-ply-symlink-escape", 'Shape "plymesh" "string filename" "meshes/escape.obj"\n',
          "outside the scene's folder",
          extra=["wire: none", "# meshes/escape.obj is a symlink out of the folder"],
          why="a symlink out of the folder")
pbrt_case("pbrt-ply-missing", 'Shape "plymesh" "string filename" "meshes/nowhere.ply"\n',
          "pbrt-ply-missing.pbrt:2:17: PLY file cannot be read",
          why="the file is neither on disk nor in the package")
pbrt_case("pbrt-ply-not-ply", 'Shape "plymesh" "string filename" "meshes/part.obj"\n',
          "PLY file 'meshes/part.obj' cannot be used: not a PLY file (no 'ply' line)",
          extra=["file: meshes/part.obj = meshes/part.obj"], why="an OBJ named as a PLY")
pbrt_case("pbrt-texture-absolute-path",
          'Texture "t" "spectrum" "imagemap" "string filename" "/etc/passwd"\n',
          "refused texture path: absolute path '/etc/passwd'", why="an absolute texture path")
pbrt_case("pbrt-point-light", 'LightSource "point" "rgb I" [1 1 1]\n',
          'pbrt-point-light.pbrt:2:1: LightSource "point" is not modelled', why="a delta light")
pbrt_case("pbrt-negative-radiance", 'AreaLightSource "diffuse" "rgb L" [-1 0 0]\n',
          "radiance L must be finite and not negative", why="a negative emitter")
pbrt_case("pbrt-no-worldend", "WorldBegin\n" + PBRT_LIGHT,
          "the file ends before WorldEnd", world=False, why="the scene is never closed")
pbrt_case("pbrt-no-light", "WorldBegin\nWorldEnd\n",
          "pbrt-no-light.pbrt:2:1: the scene has no area light", world=False, why="nothing emits")
pbrt_case("pbrt-attribute-end-unmatched", "AttributeEnd\n",
          "pbrt-attribute-end-unmatched.pbrt:2:1: AttributeEnd without a matching AttributeBegin",
          why="one end too many")
pbrt_case("pbrt-shape-before-world", 'Shape "sphere"\nWorldBegin\n' + PBRT_LIGHT + "WorldEnd\n",
          "pbrt-shape-before-world.pbrt:1:1: Shape before WorldBegin", world=False,
          why="geometry in the options block")

# Methods (submitted with a good scene).
def method_case(name, text, message, status="INVALID_ARGUMENT", why="", extra=()):
    write("methods", name + ".txt", text,
          ["# " + why, "status: " + status, "message: " + message] + list(extra))


method_case("empty", "", "method", why="no method")
method_case("unknown-strategy", "sparkle", "unknown strategy \"sparkle\"", why="not a strategy")
method_case("count-zero", "0*sa", "method", why="zero samples")
method_case("count-huge", "99999999999999999999*sa", "method", why="a count past 64 bits")
method_case("count-over-limit", "5000*sa", "method", why="past kMaxTermCount")
method_case("sum-over-limit", "4096*sa+4096*bsdf", "method", why="past kMaxMethodSamples")
method_case("too-many-terms", "+".join(["sa"] * 17), "more than 16 terms", why="17 terms")
method_case("direction-on-point-strategy", "sa:v", "method", why="':v' on a point strategy")
method_case("unknown-combine", "bsdf+sa/median", "unknown combination \"median\"",
            why="not a combination")
method_case("trailing-plus", "bsdf+", "method", why="a term is missing")
method_case("nul-byte", "sa\x00bsdf", "method", why="a NUL byte inside")
method_case("very-long", "sa" * 5000, "(10000 characters)", why="10 kB of text (the message "
            "quotes at most 60 characters: it must fit gRPC's status metadata)")

# Batches (the reader; with the Batches service the same through the coordinator).
def batch_case(name, text, message, why=""):
    write("batches", name + ".json", text,
          ["# " + why, "status: INVALID_ARGUMENT", "message: " + message])


good_batch = {"format": "penumbra/batch@1", "scene": "quad-over-floor",
              "methods": ["sa", {"method": "line-sa:v", "label": "ours"}],
              "budget": {"seconds": 2}}
def batch_with(change):
    batch = copy.deepcopy(good_batch)
    change(batch)
    return json.dumps(batch, indent=1)


batch_case("truncated-json", json.dumps(good_batch)[:40], "invalid JSON", why="cut short")
batch_case("deep-nesting-10000", '{"format": "penumbra/batch@1", "methods": ' + "[" * 10000 +
           "]" * 10000 + "}", "JSON nesting deeper than", why="10,000 nested arrays")
batch_case("negative-budget", batch_with(setter(["budget", "seconds"], -10)),
           "$.budget.seconds", why="a negative compute budget")
batch_case("budget-1e999", json.dumps(good_batch).replace('"seconds": 2', '"seconds": 1e999'),
           "number overflow parsing '1e999'", why="an infinite budget")
batch_case("budget-is-string", batch_with(setter(["budget", "seconds"], "10")),
           "$.budget.seconds: expected a number, got string", why="a number as a string")
batch_case("spp-zero", batch_with(setter(["budget"], {"spp": [0, 16]})), "$.budget.spp[0]",
           why="zero samples")
batch_case("spp-huge", batch_with(setter(["budget"], {"spp": [4294967296]})), "$.budget.spp[0]",
           why="2^32 samples")
batch_case("repeats-huge", batch_with(setter(["repeats"], 1000000)), "$.repeats",
           why="a million repeats")
batch_case("methods-empty", batch_with(setter(["methods"], [])), "$.methods",
           why="nothing to compare")
batch_case("method-unknown", batch_with(setter(["methods"], ["sparkle"])), "$.methods[0]",
           why="an unknown method")
batch_case("duplicate-label", batch_with(setter(["methods"], ["sa", "sa"])),
           "is used twice", why="two methods with one label")
batch_case("region-image", batch_with(setter(["regions"], {"image": [0, 0, 4, 4]})),
           "$.regions.image", why="'image' is reserved")
batch_case("too-many-methods", batch_with(setter(["methods"], [{"method": "sa", "label": "m%d" % i}
                                                              for i in range(65)])),
           "$.methods", why="65 methods")
batch_case("missing-budget", batch_with(deleter(["budget"])), "$.budget: missing required key",
           why="no budget")
batch_case("reference-spp-word", batch_with(setter(["reference"], {"spp": "lots"})),
           "$.reference.spp", why="a sized reference is \"spp\": \"auto\", not another word")
batch_case("reference-share-zero", batch_with(setter(["reference"], {"target_share": 0})),
           "$.reference.target_share", why="a reference share of zero needs infinite samples")
batch_case("reference-share-with-spp",
           batch_with(setter(["reference"], {"spp": 64, "target_share": 0.01})),
           "$.reference.target_share", why="a share sizes the reference; a given spp is not sized")
batch_case("reference-cap-negative", batch_with(setter(["reference"], {"max_seconds": -1})),
           "$.reference.max_seconds", why="a negative compute cap")


# Requests: one RPC each, in protobuf text format (`rpc:` names the method; SubmitJob by default;
# `scene: good` puts the base scene's package into spec.scene; `pad_mib: N` adds a file of N MiB
# to that package). The coordinator under test runs with --max-scene-mib 1 (messages up to
# 1 + 16 MiB).
def request_case(name, text, status, message, extra=(), why="", suffix=".textproto"):
    write("requests", name + suffix, text,
          ["# " + why, "status: " + status, "message: " + message] + list(extra))


def submit(spec, status, message, name, extra=(), why="", scene=True):
    request_case(name, "spec {\n  " + spec + "\n}\n", status, message,
                 (["scene: good"] if scene else []) + list(extra), why)


submit('method: "sa" spp: 0', "INVALID_ARGUMENT", "spec.spp: the budget must be at least 1 pass",
       "spp-zero", why="no passes")
submit('method: "sa" spp: 4294967295', "RESOURCE_EXHAUSTED", "spec.spp: 4294967295 passes exceed",
       "spp-max-uint32", why="2^32 - 1 passes")
submit('method: "sa" compute_seconds: -5', "INVALID_ARGUMENT", "spec.compute_seconds",
       "compute-seconds-negative", why="a negative budget")
submit('method: "sa" compute_seconds: nan', "INVALID_ARGUMENT", "spec.compute_seconds",
       "compute-seconds-nan", why="NaN seconds")
submit('method: "sa" compute_seconds: inf', "INVALID_ARGUMENT", "spec.compute_seconds",
       "compute-seconds-infinite", why="infinite seconds")
submit('method: "sa" compute_seconds: 1e300', "RESOURCE_EXHAUSTED",
       "spec.compute_seconds: the budget exceeds the limit", "compute-seconds-huge",
       why="1e300 seconds")
submit('method: "sa"', "INVALID_ARGUMENT", "spec.budget: give spp or compute_seconds",
       "budget-missing", why="neither spp nor seconds")
submit('method: "sa" spp: 4 tile_size: 100000', "INVALID_ARGUMENT", "spec.tile_size: 100000",
       "tile-size-huge", why="a tile larger than any image")
submit('method: "sa" spp: 4 tile_size: 1', "INVALID_ARGUMENT", "spec.tile_size: 1",
       "tile-size-one", why="a task per pixel")
submit('method: "sa" spp: 4 passes_per_task: 1000000', "INVALID_ARGUMENT",
       "spec.passes_per_task: 1000000", "passes-per-task-huge", why="a million passes a task")
submit('method: "sa" spp: 4 sampler: "lava-lamp"', "INVALID_ARGUMENT",
       "spec.sampler: unknown sampler \\\"lava-lamp\\\"".replace('\\\\', '\\').replace('\\"', '"'),
       "sampler-unknown", why="not a sample pattern")
submit('spp: 4', "INVALID_ARGUMENT", "spec.method: empty", "method-missing", why="no method")
submit('method: "sa" spp: 4', "INVALID_ARGUMENT", "spec.scene: give a scene package",
       "scene-missing", why="neither a package nor a hash", scene=False)
submit('method: "sa" spp: 4 scene_hash: "' + "a" * 64 + '"', "NOT_FOUND",
       "spec.scene_hash: no scene", "scene-hash-unknown", why="a scene never uploaded",
       scene=False)
submit('method: "sa" spp: 4 scene_hash: "../../../etc/passwd"', "NOT_FOUND",
       "spec.scene_hash: no scene", "scene-hash-path-traversal",
       why="a path where a hash belongs", scene=False)
submit('method: "sa" spp: 4 reference_job: "job-999999"', "NOT_FOUND",
       "spec.reference_job: no job", "reference-job-unknown", why="no such job")
submit('method: "sa" spp: 4 reference_exr: "not an EXR at all"', "INVALID_ARGUMENT",
       "spec.reference_exr: not a readable EXR", "reference-exr-garbage", why="bytes, not an EXR")
submit('method: "sa" spp: 1048576 passes_per_task: 1', "RESOURCE_EXHAUSTED",
       "the coordinator's queue is full", "queue-overflow",
       why="2^20 tasks of one pass each, past the queue limit")
submit('method: "sa" spp: 4', "RESOURCE_EXHAUSTED", "spec.scene: ", "scene-over-limit",
       extra=["pad_mib: 2"], why="a 2 MiB package past --max-scene-mib 1")
submit('method: "sa" spp: 4', "RESOURCE_EXHAUSTED", "Received message larger than max",
       "message-over-limit", extra=["pad_mib: 18"],
       why="an 18 MiB message past the server's 17 MiB message limit")
submit('method: "sa" spp: 4 scene { scene_json: "{\\"format\\": \\"penumbra/scene@1\\"" }',
       "INVALID_ARGUMENT", "scene: $: invalid JSON", "scene-json-truncated",
       why="a package whose scene text ends early", scene=False)
submit('method: "sa" spp: 4 scene { scene_json: "' +
       json.dumps(json.dumps(GOOD_SCENE))[1:-1].replace("'", "\\'") + '" files { key: "../x.obj" '
       'value: "v 0 0 0" } }', "OK", "", "package-extra-escaping-file",
       why="a package carrying an unnamed '../' file: ignored (never written, never hashed)",
       scene=False)
request_case("get-job-unknown", 'job_id: "job-424242"\n', "NOT_FOUND", "no job",
             ["rpc: /penumbra.v1.Jobs/GetJob"], why="a job that never existed")
request_case("get-job-path", 'job_id: "../../etc/passwd"\n', "NOT_FOUND", "no job",
             ["rpc: /penumbra.v1.Jobs/GetJob"], why="a path as a job id")
request_case("get-job-overflow", 'job_id: "job-99999999999999999999999"\n', "NOT_FOUND", "no job",
             ["rpc: /penumbra.v1.Jobs/GetJob"], why="an id past 64 bits")
request_case("cancel-job-unknown", 'job_id: "job-424242"\n', "NOT_FOUND", "no job",
             ["rpc: /penumbra.v1.Jobs/CancelJob"], why="cancel what does not exist")
request_case("register-zero-threads", 'name: "w" threads: 0 protocol_version: PROTOCOL_VERSION_CURRENT\n',
             "INVALID_ARGUMENT", "threads", ["rpc: /penumbra.v1.Workers/Register",
                                             "fill: build_flavour"], why="a worker without threads")
request_case("register-foreign-build", 'name: "w" threads: 1 build_flavour: "GNU-1-vax" '
             'protocol_version: PROTOCOL_VERSION_CURRENT\n', "FAILED_PRECONDITION",
             "different bits", ["rpc: /penumbra.v1.Workers/Register"],
             why="a worker that would render other bits")
request_case("heartbeat-unknown-worker", 'worker_id: "w-ghost" attempt_tokens: "x"\n',
             "NOT_FOUND", "w-ghost", ["rpc: /penumbra.v1.Workers/Heartbeat"],
             why="a worker that never registered")
request_case("lease-unknown-worker", 'worker_id: "w-ghost" max_tasks: 4294967295\n',
             "NOT_FOUND", "w-ghost", ["rpc: /penumbra.v1.Workers/LeaseTasks"],
             why="leases for nobody, as many as possible")
request_case("get-scene-unknown", 'scene_hash: "' + "0" * 64 + '"\n', "NOT_FOUND", "no scene",
             ["rpc: /penumbra.v1.Workers/GetScene"], why="a scene never uploaded")
request_case("get-scene-path", 'scene_hash: "../../data/penumbra.db"\n', "NOT_FOUND", "no scene",
             ["rpc: /penumbra.v1.Workers/GetScene"], why="a path as a scene hash")
request_case("get-scene-manifest-unknown", 'scene_hash: "' + "0" * 64 + '"\n', "NOT_FOUND",
             "no scene", ["rpc: /penumbra.v1.Workers/GetSceneManifest"],
             why="the chunks of a scene never uploaded")
request_case("start-upload-over-limit", 'scene_hash: "' + "0" * 64 + '" total_bytes: 1099511627776 '
             'chunk_bytes: 1048576\n', "RESOURCE_EXHAUSTED",
             "exceeds the coordinator's scene-size limit",
             ["rpc: /penumbra.v1.Jobs/StartSceneUpload"], why="a 1 TiB scene announced")
request_case("start-upload-missing-hashes", 'scene_hash: "' + "0" * 64 + '" total_bytes: 9000 '
             'chunk_bytes: 4096 chunk_hashes: "' + "1" * 64 + '"\n', "INVALID_ARGUMENT",
             "manifest.chunk_hashes: 1 hashes for 9000 bytes",
             ["rpc: /penumbra.v1.Jobs/StartSceneUpload"], why="fewer chunk hashes than chunks")
request_case("complete-task-garbage-tile", 'worker_id: "w-ghost" job_id: "job-1" attempt_token: "t" '
             'tile: "PNT1 and then nothing"\n', "INVALID_ARGUMENT", "tile: tile bytes",
             ["rpc: /penumbra.v1.Workers/CompleteTask"], why="a result tile that is not one")
request_case("complete-task-negative-seconds", 'worker_id: "w-ghost" job_id: "job-1" '
             'attempt_token: "t" compute_seconds: -1\n', "INVALID_ARGUMENT",
             "compute_seconds", ["rpc: /penumbra.v1.Workers/CompleteTask", "fill: tile"],
             why="negative compute time (with a well-formed 1x1 tile)")
request_case("complete-task-nan-seconds", 'worker_id: "w-ghost" job_id: "job-1" '
             'attempt_token: "t" compute_seconds: nan\n', "INVALID_ARGUMENT",
             "compute_seconds", ["rpc: /penumbra.v1.Workers/CompleteTask", "fill: tile"],
             why="NaN compute time (with a well-formed 1x1 tile)")
# A request that does not parse never reaches the coordinator's code: gRPC's server answers
# UNIMPLEMENTED with an empty message (its choice, not ours).
request_case("submit-not-protobuf", "\xff\xff\xff\xff garbage", "UNIMPLEMENTED", "",
             ["rpc: /penumbra.v1.Jobs/SubmitJob", "raw: yes"], why="bytes that are no message",
             suffix=".bin")
request_case("submit-nested-groups-10000", "\x7b" * 10000, "UNIMPLEMENTED", "",
             ["rpc: /penumbra.v1.Jobs/SubmitJob", "raw: yes"],
             why="10,000 nested protobuf groups (past the parser's recursion limit)", suffix=".bin")

# Methods that parse but cannot run on the scene: the coordinator builds the estimator at
# submission, so they are refused there (not after a worker's retries).
submit('method: "line-sa:rand" spp: 4', "INVALID_ARGUMENT", ":rand\" is not defined",
       "submit-line-direction-rand", why="a line direction with no point pdf")
submit('method: "psa+sa/weighted" spp: 4', "INVALID_ARGUMENT",
       "combines one psa term and one ltc term", "submit-peters-weights-without-ltc",
       why="a combination that needs psa and ltc")
