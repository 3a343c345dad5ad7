"""Traces a shadow-ray set dumped by `cargo bench -p shadow-hard --bench rays` through Embree (the
embreex binding: `pip install numpy embreex`), one thread, and writes its answers beside the set.

Usage: python3 embree_rays.py DIR NAME
Reads DIR/NAME.tris (float32 x 9 per triangle) and DIR/NAME.rays (float32 x 7 per ray: origin,
direction, far distance); writes DIR/NAME.embree (one byte per ray, 1 occluded) and prints one line:
build_ms=... upload_ms=... trace_ms=... rays=...
"""

import sys
import time

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh

# Scene builds per run; the median is reported.
BUILDS = 3


def main(folder, name):
    tris = np.fromfile(f"{folder}/{name}.tris", dtype="<f4").reshape(-1, 3, 3)
    rays = np.fromfile(f"{folder}/{name}.rays", dtype="<f4").reshape(-1, 7)
    origins = np.ascontiguousarray(rays[:, 0:3])
    directions = np.ascontiguousarray(rays[:, 3:6])
    far = np.ascontiguousarray(rays[:, 6])

    # The binding copies the triangles into Embree's buffers (the upload); the scene's BVH is built when
    # it is committed, on its first query (the build, with one ray). Built BUILDS times in a row, as the
    # bench builds ours, and the median kept.
    builds = []
    for _ in range(BUILDS):
        start = time.perf_counter()
        scene = rtcs.EmbreeScene()
        TriangleMesh(scene, tris)
        upload = time.perf_counter() - start
        start = time.perf_counter()
        scene.run(origins[:1], directions[:1], query="OCCLUDED", dists=far[:1])
        builds.append(time.perf_counter() - start)
    build = sorted(builds)[len(builds) // 2]

    start = time.perf_counter()
    hits = scene.run(origins, directions, query="OCCLUDED", dists=far)
    trace = time.perf_counter() - start

    # embreex answers 0 for an occluded ray and -1 for a free one.
    (hits == 0).astype(np.uint8).tofile(f"{folder}/{name}.embree")
    print(f"build_ms={build * 1e3:.3f} upload_ms={upload * 1e3:.3f} trace_ms={trace * 1e3:.3f} rays={len(rays)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
