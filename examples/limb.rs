//! Cooper & Maddock's limb (§5): two kinematic bones inside a slab of tissue bound to them
//! with `attach_nodes_inside`; the lower bone turns about the hinge at 10°/s up to 110°. One
//! run per model, 2D and 3D, printing the angle at which each model first inverts an element.
//!
//! ```text
//! cargo run --release --example limb [-- --spacing 0.1 --young 1e4]
//! ```

use std::env;

fn arg<T: std::str::FromStr>(name: &str, default: T) -> T {
    let args: Vec<String> = env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

macro_rules! run_dimension {
    ($dim:ident, $label:expr) => {{
        use sinew::$dim::scenes::LimbScene;
        use sinew::$dim::ElementModel;
        let base = LimbScene {
            spacing: arg("--spacing", 0.1),
            young_modulus: arg("--young", 1e4),
            ..LimbScene::default()
        };
        for model in ElementModel::ALL {
            let scene = LimbScene { model, ..base };
            match scene.run() {
                Ok(o) => println!(
                    "{:<3} {:<18} nodes {:>5} cells {:>5} bound {:>4}  first inversion {:>8}  max inverted {:>4}  min volume ratio {:+.3}  anchor error {:.1e} m  wall {:.2} s{}",
                    $label,
                    model.name(),
                    o.nodes,
                    o.elements,
                    o.attached_nodes,
                    o.first_inversion_degrees.map_or("none".to_string(), |a| format!("{a:.1}°")),
                    o.max_inverted_elements,
                    o.min_volume_ratio,
                    o.max_anchor_error,
                    o.wall_seconds,
                    if o.non_finite { "  NON-FINITE" } else { "" }
                ),
                Err(e) => println!("{:<3} {:<18} failed to build: {e}", $label, model.name()),
            }
        }
    }};
}

fn main() {
    println!("limb: lower bone turned at 10°/s to 110°, tissue E = 1e4 Pa, 1000 kg/m³, no gravity");
    run_dimension!(dim2, "2D");
    run_dimension!(dim3, "3D");
}
