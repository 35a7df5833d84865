#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_task_decoding (fuzz/corpus/task_decoding/): tasks encoded with
`protoc --encode=penumbra.v1.Task` and result tiles in TileAccumulator's serialized layout
(core/render/tile.cpp), framed as task_decoding_fuzz.cpp reads them; and scene manifests
(`protoc --encode=penumbra.v1.SceneManifest`) with a chunk (flag bit 1). Run from the repository root."""
import hashlib
import os
import struct
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fuzz", "corpus", "task_decoding")
HASH = "0123456789abcdef" * 4


def encode_task(text, message="penumbra.v1.Task"):
    return subprocess.run(
        ["protoc", "--proto_path=" + os.path.join(ROOT, "proto"),
         "--encode=" + message, "penumbra/v1/farm.proto"],
        input=text.encode(), capture_output=True, check=True).stdout


def encode_manifest(total, chunk_bytes, hashes, scene_hash=HASH):
    text = 'scene_hash: "%s" total_bytes: %d chunk_bytes: %d ' % (scene_hash, total, chunk_bytes)
    text += " ".join('chunk_hashes: "%s"' % h for h in hashes)
    return encode_task(text, "penumbra.v1.SceneManifest")


def tile_bytes(x0, y0, x1, y1, passes, value=0.5):
    pixels = (x1 - x0) * (y1 - y0)
    fixed = int(value * passes * 2**32)
    fixed_square = int(value * value * passes * 2**32)
    out = struct.pack("<I4iQ", 0x31544e50, x0, y0, x1, y1, 0)
    out += b"".join(fixed.to_bytes(16, "little", signed=True) for _ in range(3 * pixels))
    out += b"".join(fixed_square.to_bytes(16, "little", signed=True) for _ in range(3 * pixels))
    out += struct.pack("<%dI" % pixels, *([passes] * pixels))
    return out


def task_text(method="sa", sampler="stratified", tile=(0, 0, 4, 4), passes=(0, 4),
              scene_hash=HASH):
    return ('job_id: "job-1" task_index: 3 attempt_token: "t-1-3-1" scene_hash: "%s" '
            'method: "%s" sampler: "%s" seed: 7 tile { x0: %d y0: %d x1: %d y1: %d } '
            'pass_begin: %d pass_end: %d' % ((scene_hash, method, sampler) + tile + passes))


def write(name, flags, task, tile=b""):
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(bytes([flags]) + struct.pack("<H", len(task)) + task + tile)


os.makedirs(OUT, exist_ok=True)
write("good-task-good-tile", 1, encode_task(task_text()), tile_bytes(0, 0, 4, 4, 4))
write("good-task-corner-tile", 1,
      encode_task(task_text(method="bsdf+line-sa:v/power", sampler="sobol", tile=(12, 8, 16, 12),
                            passes=(8, 10))),
      tile_bytes(12, 8, 16, 12, 2, value=3.0))
write("tile-wrong-counts", 1, encode_task(task_text()), tile_bytes(0, 0, 4, 4, 3))
write("tile-other-rect", 1, encode_task(task_text()), tile_bytes(0, 0, 2, 4, 4))
write("tile-outside-image", 1, encode_task(task_text(tile=(8, 8, 20, 12))))
write("empty-pass-range", 1, encode_task(task_text(passes=(5, 5))))
write("negative-tile", 1, encode_task(task_text(tile=(-4, 0, 4, 4))))
write("unknown-method", 1, encode_task(task_text(method="sparkle")))
write("unknown-sampler", 1, encode_task(task_text(sampler="lava-lamp")))
write("hash-escaping", 0, encode_task(task_text(scene_hash="../../etc/passwd")))
write("hash-of-another-scene", 0, encode_task(task_text()))
write("empty-task", 0, b"")

# Scene manifests and chunks (flag 2; with 4: the first chunk hash is the chunk's own SHA-256).
chunk = bytes(range(256)) * 20  # 5120 bytes
chunk_hash = hashlib.sha256(chunk).hexdigest()
write("manifest-one-chunk", 2, encode_manifest(len(chunk), 8192, [chunk_hash]), chunk)
write("manifest-two-chunks", 6, encode_manifest(4096 + 5120, 4096, [HASH, HASH]), chunk[:4096])
write("manifest-last-chunk-short", 6, encode_manifest(9000, 4096, [HASH, HASH, HASH]), chunk[:4096])
write("manifest-too-few-hashes", 2, encode_manifest(9000, 4096, [HASH]), chunk)
write("manifest-chunk-too-small", 2, encode_manifest(100, 16, [HASH]), chunk[:100])
write("manifest-bad-scene-hash", 2, encode_manifest(100, 4096, [HASH], scene_hash="../x"))
write("manifest-over-limit", 2, encode_manifest(1 << 40, 1 << 21, [HASH]))
