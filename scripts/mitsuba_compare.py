#!/usr/bin/env python3
"""Compare volcache's 3D path tracer with Mitsuba 3 (volpath, scalar_rgb).

A development tool, not part of CI. Needs `pip install mitsuba numpy` and a release
build (`cargo build --release`). For each scene it converts the volcache JSON to a
Mitsuba scene dictionary, renders both renderers twice (two seeds), and reports:

- the RMSE of luminance between volcache and Mitsuba, against the RMSE expected
  from noise alone, sqrt((RMSE(v1, v2)² + RMSE(m1, m2)²) / 2), whose ratio is ~1
  for unbiased, agreeing renderers;
- the same on 8×8-pixel block means (less noise, so it exposes bias better);
- the mean luminance of each image with its standard error (over blocks).

Usage: scripts/mitsuba_compare.py [scenes3d/fog_box.json scenes3d/mesh_in_fog.json]
       [--res 128x128] [--spp 256] [--out out/mitsuba]

Conversion notes: quads → `rectangle`, boxes → `cube`, OBJ → `obj`, diffuse
(wrapped in `twosided` when two-sided), emission → one-sided `area` emitters (the
only kind Mitsuba has), point → `point`, sun → `directional` (its small cone is
dropped), sky → `constant`. A medium box becomes a `cube` with a `null` BSDF shrunk
by 1e-3 of its size, so its faces never coincide with walls (Mitsuba would lose
track of the medium there); the camera gets the medium when it is inside.
"""

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
T = mi.ScalarTransform4f
ROOT = Path(__file__).resolve().parent.parent


def rgb(c):
    return [float(c)] * 3 if isinstance(c, (int, float)) else [float(x) for x in c]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def material(s):
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb(s.get("reflectance", 0))}}
    return {"type": "twosided", "bsdf": bsdf} if s.get("two_sided", True) else bsdf


def shape(s, base):
    if "quad" in s:
        q = s["quad"]
        u, v, o = q["u"], q["v"], q["origin"]
        n = normalize(cross(u, v))
        c = [o[k] + 0.5 * (u[k] + v[k]) for k in range(3)]
        m = [[0.5 * u[r], 0.5 * v[r], n[r], c[r]] for r in range(3)] + [[0, 0, 0, 1]]
        d = {"type": "rectangle", "to_world": T(m)}
    elif "box" in s:
        b = s["box"]
        lo, hi = b["min"], b["max"]
        c = [(lo[k] + hi[k]) / 2 for k in range(3)]
        h = [(hi[k] - lo[k]) / 2 for k in range(3)]
        to_world = T().translate(c).rotate([0, 1, 0], b.get("rotate_y_deg", 0.0)).scale(h)
        d = {"type": "cube", "to_world": to_world}
    else:
        m = s["mesh"]
        sc = m.get("scale", 1.0)
        sc = [sc] * 3 if isinstance(sc, (int, float)) else sc
        to_world = T().translate(m.get("translate", [0, 0, 0])).scale(sc)
        d = {"type": "obj", "filename": str(base / m["path"]), "to_world": to_world, "face_normals": True}
    d["bsdf"] = material(s)
    e = rgb(s.get("emission", 0))
    if max(e) > 0:
        d["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": e}}
    return d


def convert(scene_path, res, spp, seed):
    sd = json.loads(Path(scene_path).read_text())
    base = Path(scene_path).parent
    r = sd.get("render", {})
    cam = sd["camera"]
    md = {"type": "scene", "integrator": {"type": "volpath", "max_depth": r.get("max_depth", 64) + 1, "rr_depth": 5}}
    sensor = {
        "type": "perspective",
        "fov": cam["fov_deg"],
        "fov_axis": "y",
        "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
        "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        "film": {"type": "hdrfilm", "width": res[0], "height": res[1], "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
    }
    for i, s in enumerate(sd.get("shapes", [])):
        md[f"shape{i}"] = shape(s, base)
    for i, l in enumerate(sd.get("lights", [])):
        (kind, p), = l.items()
        if kind == "point":
            md[f"light{i}"] = {"type": "point", "position": p["position"],
                               "intensity": {"type": "rgb", "value": rgb(p["intensity"])}}
        elif kind == "sun":
            md[f"light{i}"] = {"type": "directional", "direction": p["direction"],
                               "irradiance": {"type": "rgb", "value": rgb(p["irradiance"])}}
        else:
            md[f"light{i}"] = {"type": "constant", "radiance": {"type": "rgb", "value": rgb(p["radiance"])}}
    m = sd.get("medium")
    if m:
        sa, ss = np.array(rgb(m["sigma_a"])), np.array(rgb(m["sigma_s"]))
        st = sa + ss
        albedo = np.where(st > 0, ss / np.where(st > 0, st, 1), 0)
        medium = {"type": "homogeneous", "sigma_t": {"type": "rgb", "value": st.tolist()},
                  "albedo": {"type": "rgb", "value": albedo.tolist()}, "scale": 1.0,
                  "phase": {"type": "hg", "g": m.get("g", 0.0)}}
        region = m.get("region", "everywhere")
        if region == "everywhere":
            sensor["medium"] = medium
        else:
            lo, hi = np.array(region["box"]["min"]), np.array(region["box"]["max"])
            h = (hi - lo) / 2 * (1 - 1e-3)
            c = (lo + hi) / 2
            md["medium_box"] = {"type": "cube", "to_world": T().translate(c.tolist()).scale(h.tolist()),
                                "bsdf": {"type": "null"}, "interior": medium}
            p = np.array(cam["position"])
            if np.all(np.abs(p - c) < h):
                sensor["medium"] = medium
    md["sensor"] = sensor
    return md


def luminance(img):
    return img[..., 0] * 0.2126 + img[..., 1] * 0.7152 + img[..., 2] * 0.0722


def mitsuba_render(scene_path, res, spp, seed):
    scene = mi.load_dict(convert(scene_path, res, spp, seed))
    return np.array(mi.render(scene, seed=seed), dtype=np.float64)[..., :3]


def volcache_render(scene_path, res, spp, seed, out):
    exe = ROOT / "target" / "release" / "volcache"
    subprocess.run([str(exe), "render3d", str(scene_path), "--res", f"{res[0]}x{res[1]}", "--spp", str(spp),
                    "--seed", str(seed), "--quiet", "--out", str(out)], check=True)
    stem = Path(scene_path).stem
    bmp = mi.Bitmap(str(out / f"{stem}_pt.exr"))
    return np.array(bmp, dtype=np.float64)[..., :3]


def rmse(a, b):
    return float(np.sqrt(np.mean((luminance(a) - luminance(b)) ** 2)))


def blocks(img, k=8):
    h, w = img.shape[0] // k * k, img.shape[1] // k * k
    return img[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def compare(scene_path, res, spp, out):
    v = [volcache_render(scene_path, res, spp, s, out / f"v{s}") for s in (1, 2)]
    m = [mitsuba_render(scene_path, res, spp, s) for s in (1, 2)]
    mi.Bitmap(m[0].astype(np.float32)).write(str(out / f"{Path(scene_path).stem}_mitsuba.exr"))
    report = {"scene": str(scene_path), "resolution": res, "spp": spp}
    for name, f in (("pixels", lambda x: x), ("blocks8", blocks)):
        vv, mm = [f(x) for x in v], [f(x) for x in m]
        expected = math.sqrt((rmse(*vv) ** 2 + rmse(*mm) ** 2) / 2)
        measured = [rmse(vv[0], mm[0]), rmse(vv[1], mm[1])]
        report[name] = {"rmse_volcache_vs_mitsuba": measured, "rmse_expected_from_noise": expected,
                        "ratio": [x / expected for x in measured]}
    # Image-mean luminance: mean of the two seeds, standard error |a − b| / 2.
    for name, imgs in (("volcache", v), ("mitsuba", m)):
        a, b = (float(luminance(x).mean()) for x in imgs)
        report[f"mean_luminance_{name}"] = [(a + b) / 2, abs(a - b) / 2]
    return report


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="*", default=["scenes3d/fog_box.json", "scenes3d/mesh_in_fog.json"])
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--out", default="out/mitsuba")
    a = ap.parse_args()
    res = [int(x) for x in a.res.split("x")]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    reports = [compare(Path(s), res, a.spp, out) for s in a.scenes]
    text = json.dumps(reports, indent=2)
    (out / "mitsuba_compare.json").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    sys.exit(main())
