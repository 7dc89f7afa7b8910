#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets (tests/fuzz/corpus/<target>/).

The seeds are small valid (and a few nearly valid) inputs made from the repository's own
scenarios and from the file formats as segslam writes them. Re-run after a format change:
    python3 tests/fuzz/make_seed_corpus.py
Standard library only, so that it runs anywhere; the output is committed.
"""
import hashlib
import json
import pathlib
import struct
import zlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = ROOT / "tests" / "fuzz" / "corpus"


def write(target, name, data):
    path = CORPUS / target / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data if isinstance(data, bytes) else data.encode())


def png(width, height, rows, bit_depth, color_type):
    """A PNG of `rows` (lists of samples), as libpng would write it, no filter."""
    channels = {0: 1, 2: 3, 6: 4}[color_type]
    raw = bytearray()
    for row in rows:
        raw.append(0)
        for sample in row:
            raw += struct.pack(">H", sample) if bit_depth == 16 else bytes([sample])
    assert all(len(r) == width * channels for r in rows) and len(rows) == height

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw)))
            + chunk(b"IEND", b""))


def rle_counts(mask):
    """COCO RLE counts of a row-major 0/1 mask, in column-major order."""
    height, width = len(mask), len(mask[0])
    counts, current, run = [], 0, 0
    for x in range(width):
        for y in range(height):
            if mask[y][x] != current:
                counts.append(run)
                current, run = mask[y][x], 0
            run += 1
    counts.append(run)
    return counts


def rle_string(counts):
    """pycocotools' rleToString."""
    out = []
    for i, count in enumerate(counts):
        x = count - counts[i - 2] if i > 2 else count
        more = True
        while more:
            c = x & 0x1f
            x >>= 5
            more = (x != -1) if (c & 0x10) else (x != 0)
            if more:
                c |= 0x20
            out.append(chr(c + 48))
    return "".join(out)


def scenario_seeds():
    for path in sorted((ROOT / "scenarios" / "test").glob("*.yaml")):
        write("scenario", path.name, path.read_bytes())
    for name in ("office_walking_xyz.yaml", "city_street_grid.yaml"):
        write("scenario", name, (ROOT / "scenarios" / name).read_bytes())


def tum_list_seeds():
    stamps = [i / 30 for i in range(6)]
    header = "# color images\n# file: 'segslam'\n# timestamp filename\n"
    write("tum_lists", "rgb.txt", header + "".join(f"{s:.6f} rgb/{s:.6f}.png\n" for s in stamps))
    write("tum_lists", "associations.txt",
          "".join(f"{s:.6f} rgb/{s:.6f}.png {s + 0.004:.6f} depth/{s + 0.004:.6f}.png\n" for s in stamps))
    write("tum_lists", "camera.yaml",
          "# Pinhole intrinsics in pixels (OpenCV convention: pixel centres at integers).\n"
          "width: 640\nheight: 480\nfx: 525.0\nfy: 525.0\ncx: 319.5\ncy: 239.5\ndepth_factor: 5000\n")
    write("tum_lists", "camera_distorted.yaml",
          "width: 640\nheight: 480\nfx: 517.3\nfy: 516.5\ncx: 318.6\ncy: 255.3\ndepth_factor: 5000\n"
          "k1: 0.2624\nk2: -0.9531\np1: -0.0054\np2: 0.0026\nk3: 1.1633\n")


def trajectory_seeds():
    lines = [
        "# ground truth trajectory (camera-to-world T_wc, written by segslam)",
        "# timestamp tx ty tz qx qy qz qw",
        "0.000000 -0.57605756 0.117372152 1.38095282 -0.575190463 0.567883022 -0.407759122 0.424732037",
        "0.033333 -0.57012 0.11801 1.38102 -0.575001 0.568012 -0.407801 0.424799",
        "0.066667 -0.56410 0.11866 1.38110 -0.574810 0.568140 -0.407842 0.424866",
        "1305031102.175304 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248",
    ]
    write("trajectory", "groundtruth.txt", "\n".join(lines[:5]) + "\n")
    write("trajectory", "tum_freiburg.txt", lines[1] + "\n" + lines[5] + "\n")


def instance_mask_seeds():
    table = {"instances": [
        {"category": "person", "category_id": 1, "id": 1, "moveable": True},
        {"category": "car", "category_id": 3, "id": 2, "moveable": True},
        {"category": "tv", "category_id": 72, "id": 7, "moveable": False},
    ]}
    text = json.dumps(table, indent=2, sort_keys=True) + "\n"
    ids = [[0] * 16 for _ in range(12)]
    for y in range(2, 9):
        for x in range(3, 7):
            ids[y][x] = 1
    for y in range(5, 12):
        for x in range(9, 15):
            ids[y][x] = 2
    ids[0][0] = 7
    write("instance_mask", "table_and_mask", text.encode() + png(16, 12, ids, 16, 0))
    write("instance_mask", "mask_unknown_id", text.encode() + png(4, 3, [[0, 0, 0, 0], [0, 9, 9, 0], [0, 0, 0, 0]], 16, 0))
    write("instance_mask", "table_only", text)
    write("instance_mask", "colour_png", b"{\"instances\": []}\n" + png(4, 3, [[10, 20, 30] * 4] * 3, 8, 2))
    write("instance_mask", "depth_png", b"{}" + png(4, 2, [[5000, 0, 65535, 1], [1, 2, 3, 4]], 16, 0))


def coco_seeds():
    # Frames of the target's sequence: 16x12, stems 1.000000, 2.000000, 3.000000.
    mask = [[1 if 3 <= x < 9 and 2 <= y < 8 else 0 for x in range(16)] for y in range(12)]
    counts = rle_counts(mask)
    results = [
        {"image_id": "1.000000", "category_id": 1, "score": 0.9,
         "segmentation": {"size": [12, 16], "counts": rle_string(counts)}},
        {"image_id": "2.000000", "category_id": 3, "score": 0.7,
         "segmentation": {"size": [12, 16], "counts": counts}},
        {"image_id": "3.000000", "category_id": 1, "score": 0.6,
         "segmentation": [[2.0, 2.0, 10.5, 2.0, 10.5, 9.0, 2.0, 9.0]]},
    ]
    write("coco", "results_by_stem.json", json.dumps(results))
    by_id = [dict(r, image_id=i + 1) for i, r in enumerate(results)]
    write("coco", "results_by_id.json", json.dumps(by_id))
    dataset = {
        "images": [{"id": 10 + i, "file_name": f"rgb/{i + 1}.000000.png", "width": 16, "height": 12}
                   for i in range(3)],
        "categories": [{"id": 1, "name": "person"}, {"id": 2, "name": "car"}],
        "annotations": [
            {"id": 1, "image_id": 10, "category_id": 1, "iscrowd": 0,
             "segmentation": {"size": [12, 16], "counts": rle_string(counts)}},
            {"id": 2, "image_id": 11, "category_id": 2, "iscrowd": 1,
             "segmentation": {"size": [12, 16], "counts": counts}},
            {"id": 3, "image_id": 12, "category_id": 2, "iscrowd": 0, "score": 0.8,
             "segmentation": [[1, 1, 6, 1, 6, 5], [8, 8, 12, 8, 12, 11, 8, 11]]},
        ],
    }
    write("coco", "dataset.json", json.dumps(dataset))


def map_file_seeds():
    def f64(v):
        return struct.pack("<d", v)

    payload = struct.pack("<ii", 16, 12) + f64(20) + f64(20) + f64(7.5) + f64(5.5)
    description = b"fuzz seed: office_small, mode mutual"
    payload += struct.pack("<Q", len(description)) + description
    keyframes = [(1, 0.0, 0.0), (4, 0.1, 0.25)]
    payload += struct.pack("<Q", len(keyframes))
    for kf_id, stamp, tx in keyframes:
        payload += struct.pack("<Q", kf_id) + f64(stamp)
        for row in range(3):
            payload += b"".join(f64(1.0 if col == row else (tx if (row, col) == (0, 3) else 0.0))
                                for col in range(4))
    points = [(7, (0.5, -0.2, 2.0)), (9, (1.0, 0.3, 3.5)), (12, (-0.4, 0.1, 1.2))]
    payload += struct.pack("<Q", len(points))
    for point_id, position in points:
        payload += struct.pack("<Q", point_id) + b"".join(f64(c) for c in position)
        payload += struct.pack("<fff", 0.0, 0.0, -1.0) + struct.pack("<ff", 0.5, 6.0)
        payload += bytes((point_id * 37 + k) % 256 for k in range(32))
        payload += struct.pack("<I", 3) + bytes([200, 120, 40])
    # Byte 0 even: the target wraps the payload in a valid header and checksum.
    write("map_file", "payload", b"\x00" + payload)
    # Byte 0 odd: the whole file as SaveLongTermMap writes it.
    whole = (b"SEGSLAM-MAP\x00" + struct.pack("<IQ", 1, len(payload)) + payload
             + hashlib.sha256(payload).digest())
    write("map_file", "whole_file", b"\x01" + whole)
    write("map_file", "whole_file_truncated", b"\x01" + whole[:40])


if __name__ == "__main__":
    scenario_seeds()
    tum_list_seeds()
    trajectory_seeds()
    instance_mask_seeds()
    coco_seeds()
    map_file_seeds()
