//! A small foggy 3D room of our own, shared by the 3D probe and app tests: a
//! floor, a box that shades part of it, a point light, a box of fog with g = 0.4,
//! a 32×24 render block (seed 3).

pub const ROOM: &str = r#"{
  "camera": {"position": [0, 1, 3], "look_at": [0, 0.8, 0], "fov_deg": 50},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.6},
    {"box": {"min": [-0.6, 0, -0.4], "max": [0.2, 1.2, -0.2]}, "reflectance": 0.5}
  ],
  "lights": [{"point": {"position": [0.3, 1.6, -1.0], "intensity": 3}}],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.6, "g": 0.4, "region": {"box": {"min": [-2, 0, -2], "max": [2, 2, 2]}}},
  "render": {"resolution": [32, 24], "spp": 4, "seed": 3, "max_depth": 8}
}"#;
