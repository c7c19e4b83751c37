#!/usr/bin/env python3
"""Speed of volcache against Embree (ray casting) and Mitsuba 3 (path tracing).

A development tool, not part of CI (it installs nothing). Run it in a venv with the
PyPI packages `embreex`, `mitsuba` and `numpy`, after `cargo build --release`:

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install embreex mitsuba numpy
    /tmp/venv/bin/python scripts/embree_mitsuba_compare.py [--rounds 5] [--core 1]

Everything runs pinned to one core (this process sets its affinity, children
inherit it; Mitsuba and Embree are also told to use one thread), and the two sides
of each ratio run interleaved, round after round, so a slow spell of a shared
machine hits both; each figure is the best of its rounds. It prints:

- closest-hit rays/s, volcache / Embree, on the 158,802-triangle UV sphere of
  `volcache bench rays3d` (the same vertices: 200 bands x 399 segments), 5M rays,
  origins uniform in [-2, 2]^3, directions uniform (rays made before timing);
- BVH build time, volcache / Embree (Embree: rtcCommitScene, timed as the first
  query after the mesh is attached; volcache: `Geometry::new`, one thread);
- camera samples/s, volcache `render3d --method pt` / Mitsuba 3 `scalar_rgb`
  `volpath`, on scenes3d/fog_box.json at equal spp, depth and Russian-roulette
  depth (the scene converted by `scripts/mitsuba_compare.py`; Mitsuba counts
  depth from 1 where volcache counts vertices from 0, hence the +1 on both).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
EXE = ROOT / "target" / "release" / "volcache"
sys.path.insert(0, str(Path(__file__).resolve().parent))


def uv_sphere(bands=200, segments=399):
    """Vertices and triangles of volcache's `mesh::uv_sphere` (same order)."""
    i = np.arange(bands + 1)[:, None]
    j = np.arange(segments + 1)[None, :]
    theta, phi = np.pi * i / bands, 2 * np.pi * j / segments
    v = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta) * np.ones_like(phi), np.sin(theta) * np.sin(phi)], -1)
    idx = lambda a, b: a * (segments + 1) + b  # noqa: E731
    tris = []
    for a in range(bands):
        for b in range(segments):
            if a + 1 < bands:
                tris.append((idx(a, b), idx(a + 1, b + 1), idx(a + 1, b)))
            if a > 0:
                tris.append((idx(a, b), idx(a, b + 1), idx(a + 1, b + 1)))
    return v.reshape(-1, 3).astype(np.float32), np.array(tris, dtype=np.int32)


def embree_round(vertices, faces, origins, directions):
    """(build seconds, closest-hit rays/s, hit fraction) of one Embree run."""
    import embreex.rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, vertices, faces)
    one = np.zeros((1, 3), np.float32)
    start = time.perf_counter()
    scene.run(one, one + 1)  # commits the scene: the build
    build = time.perf_counter() - start
    start = time.perf_counter()
    ids = scene.run(origins, directions)
    rate = len(origins) / (time.perf_counter() - start)
    return build, rate, float(np.mean(ids >= 0))


def volcache_rays_round(rays):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "rays.json"
        subprocess.run([str(EXE), "bench", "--threads", "1", "rays3d", "--sphere-only", "--rays", str(rays),
                        "--out", str(out)], check=True, capture_output=True)
        f = json.loads(out.read_text())["scenes"][0]
    return f["build_seconds"], f["closest_hit_rays_per_second_one_thread"], f["hit_fraction"]


def mitsuba_round(scene_dict, samples):
    import mitsuba as mi

    scene = mi.load_dict(scene_dict)
    start = time.perf_counter()
    mi.render(scene, seed=1)
    return samples / (time.perf_counter() - start)


def volcache_render_round(scene, res, spp):
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([str(EXE), "render3d", str(scene), "--threads", "1", "--res", f"{res[0]}x{res[1]}",
                        "--spp", str(spp), "--seed", "1", "--quiet", "--out", d], check=True, capture_output=True)
        summary = json.loads(next(Path(d).glob("*_pt.json")).read_text())
    return summary["samples_per_second"], summary["params"]["settings"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--core", type=int, default=1)
    ap.add_argument("--rays", type=int, default=5_000_000)
    ap.add_argument("--scene", default=str(ROOT / "scenes3d" / "fog_box.json"))
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--spp", type=int, default=16)
    args = ap.parse_args()
    os.sched_setaffinity(0, {args.core})
    res = tuple(int(x) for x in args.res.split("x"))

    import drjit as dr
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    dr.set_thread_count(1)
    from mitsuba_compare import convert

    vertices, faces = uv_sphere()
    rng = np.random.default_rng(11)
    origins = rng.uniform(-2, 2, (args.rays, 3)).astype(np.float32)
    z = rng.uniform(-1, 1, args.rays)
    phi = rng.uniform(0, 2 * np.pi, args.rays)
    r = np.sqrt(1 - z * z)
    directions = np.stack([r * np.cos(phi), r * np.sin(phi), z], -1).astype(np.float32)

    _, settings = volcache_render_round(args.scene, (8, 8), 1)
    scene_dict = convert(args.scene, res, args.spp, 1)
    scene_dict["integrator"]["max_depth"] = settings["max_depth"] + 1
    scene_dict["integrator"]["rr_depth"] = settings["rr_depth"] + 1
    samples = res[0] * res[1] * args.spp
    mitsuba_round(scene_dict, samples)  # warm-up (plugin loading)

    rows = {k: [] for k in ("v_build", "v_rays", "e_build", "e_rays", "v_pt", "m_pt")}
    for k in range(args.rounds):
        vb, vr, vh = volcache_rays_round(args.rays)
        eb, er, eh = embree_round(vertices, faces, origins, directions)
        vp, _ = volcache_render_round(args.scene, res, args.spp)
        mp = mitsuba_round(scene_dict, samples)
        for key, val in zip(rows, (vb, vr, eb, er, vp, mp)):
            rows[key].append(val)
        print(f"round {k + 1}: volcache build {vb:.4f} s, {vr / 1e6:.2f} M rays/s ({vh:.1%} hit); "
              f"embree build {eb:.4f} s, {er / 1e6:.2f} M rays/s ({eh:.1%} hit); "
              f"pt volcache {vp / 1e6:.3f} M samples/s, mitsuba {mp / 1e6:.3f} M samples/s", flush=True)
    best = {k: (min(v) if k.endswith("build") else max(v)) for k, v in rows.items()}
    print(f"\nbest of {args.rounds} rounds, one core, {args.rays} rays, {args.res} x {args.spp} spp, "
          f"max_depth {settings['max_depth']}, rr_depth {settings['rr_depth']} (volcache's counting):")
    print(f"closest hit: volcache {best['v_rays'] / 1e6:.2f} M rays/s, Embree {best['e_rays'] / 1e6:.2f} M rays/s, "
          f"ratio {best['v_rays'] / best['e_rays']:.2f} (target >= 0.5)")
    print(f"build: volcache {best['v_build']:.4f} s, Embree {best['e_build']:.4f} s, "
          f"ratio {best['v_build'] / best['e_build']:.2f} (target <= 1.2)")
    print(f"path tracing: volcache {best['v_pt'] / 1e6:.3f} M samples/s, Mitsuba scalar_rgb volpath "
          f"{best['m_pt'] / 1e6:.3f} M samples/s, ratio {best['v_pt'] / best['m_pt']:.2f} (target >= 2)")


if __name__ == "__main__":
    main()
