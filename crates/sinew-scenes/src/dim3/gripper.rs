//! A robot from its URDF file picking up a box: the two-finger gripper of
//! `assets/gripper/gripper.urdf` loaded into the rapier world by `rapier3d-urdf`, each of its
//! `*_pad` links meshed from its collision shape by isosurface stuffing into a soft pad bound
//! to the finger carrying it.
//!
//! The robot is position-controlled: its links are made kinematic and placed every step from
//! the joints' targets, as a robot driven by its controller (or by inverse kinematics) is. Soft
//! pads bound to the dynamic links of a jointed robot would not do: sinew's coupling moves a
//! dynamic bone as a free body within its step, and does not see the joints holding it.

use std::path::Path;
use std::time::Instant;

use rapier3d_urdf::{urdf_rs, UrdfLoaderOptions, UrdfRobot};
use sinew::dim3::math::{Real, Rotation, Vector};
use sinew::dim3::model::ElementModel;
use sinew::dim3::rapier::dynamics::{RigidBodyBuilder, RigidBodyHandle, RigidBodyType};
use sinew::dim3::rapier::geometry::{ColliderBuilder, SharedShape};
use sinew::dim3::rapier::math::Pose;
use sinew::dim3::{
    DeformableBuilder, DeformableHandle, DeformableWorld, Integrator, Material, Mesh,
};

/// Half the box's edge, m.
pub const BOX_HALF: Real = 0.05;

/// The gripper of `assets/gripper/gripper.urdf` (Z up in the file, turned to sinew's Y up)
/// closes its fingers `close` each (the 1 cm gap to the box, then the squeeze), lifts a 10 cm
/// box of `mass` by `lift` and holds it.
#[derive(Clone, Debug)]
pub struct GripperScene {
    /// The URDF file.
    pub urdf: std::path::PathBuf,
    /// The pads' model.
    pub model: ElementModel,
    /// The pads' material.
    pub material: Material,
    /// Cell size of the pads' stuffing, m.
    pub cell: Real,
    /// The box's mass, kg.
    pub mass: Real,
    /// Friction of the pads, the box and the table.
    pub friction: Real,
    /// How far each finger travels from open, m.
    pub close: Real,
    /// The lift, m.
    pub lift: Real,
    /// Seconds: settle, close, lift, hold.
    pub timeline: [Real; 4],
    /// Step length, s.
    pub dt: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for GripperScene {
    /// Edge-repulsion pads at 1.5 cm cells, 1100 kg/m³, E = 2·10⁵ Pa, ν = 0.3, ζ = 0.3 (the
    /// pinch scene's); a 0.2 kg box; friction 1; each finger closes 15 mm (a 5 mm squeeze),
    /// lifts 0.2 m in 1 s and holds 1 s, after 0.25 s to settle and 0.5 s to close; 60 Hz,
    /// `Integrator::Auto`.
    fn default() -> Self {
        GripperScene {
            urdf: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/gripper/gripper.urdf"),
            model: ElementModel::EdgeRepulsion,
            material: Material {
                density: 1100.0,
                young_modulus: 2e5,
                poisson_ratio: 0.3,
                damping_ratio: 0.3,
            },
            cell: 0.015,
            mass: 0.2,
            friction: 1.0,
            close: 0.015,
            lift: 0.2,
            timeline: [0.25, 0.5, 1.0, 1.0],
            dt: 1.0 / 60.0,
            integrator: Integrator::Auto { iterations: 2 },
        }
    }
}

/// A soft pad: its deformable and how it was made.
#[derive(Copy, Clone, Debug)]
pub struct Pad {
    /// The pad's deformable.
    pub handle: DeformableHandle,
    /// Its nodes.
    pub nodes: usize,
    /// Its cells.
    pub cells: usize,
    /// Nodes bound to the finger.
    pub bound: usize,
}

/// A link the joints move: its body, where it was built and its prismatic ancestors (joint
/// name, axis).
struct Chain {
    body: RigidBodyHandle,
    built: Vector,
    joints: Vec<(String, Vector)>,
}

/// The built scene, stepped by [`Gripper::step`].
pub struct Gripper {
    /// The world: table, box, robot, pads.
    pub world: DeformableWorld,
    /// The box.
    pub box_body: RigidBodyHandle,
    /// The pads, left then right.
    pub pads: Vec<Pad>,
    /// The left finger's body.
    pub finger: RigidBodyHandle,
    /// The links the joints move.
    chains: Vec<Chain>,
    scene: GripperScene,
    steps: usize,
}

/// What a run measured.
#[derive(Clone, Debug)]
pub struct GripperRecord {
    /// The pads, left then right.
    pub pads: Vec<Pad>,
    /// How far the box's bottom ends above the table, m.
    pub lifted: Real,
    /// The largest change of the box's height against the finger's from the start of the lift
    /// on, m.
    pub slip: Real,
    /// The box's lowest bottom, m (negative: into the table).
    pub lowest: Real,
    /// Wall time of each step, s.
    pub step_seconds: Vec<f64>,
}

impl GripperScene {
    /// The world, the robot and its pads.
    pub fn build(&self) -> Result<Gripper, String> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.physics.insert_collider(
            ColliderBuilder::new(SharedShape::halfspace(Vector::Y)).friction(self.friction),
            None,
        );
        let (box_body, _) = world.physics.insert(
            RigidBodyBuilder::dynamic().translation(Vector::Y * BOX_HALF),
            ColliderBuilder::cuboid(BOX_HALF, BOX_HALF, BOX_HALF)
                .density(self.mass / (2.0 * BOX_HALF).powi(3))
                .friction(self.friction),
        );
        let turn = Rotation::from_rotation_x(-std::f64::consts::FRAC_PI_2 as Real);
        let options = UrdfLoaderOptions {
            make_roots_fixed: true,
            shift: Pose::from_rotation(turn),
            ..Default::default()
        };
        let (robot, urdf) = UrdfRobot::from_file(&self.urdf, options, None)
            .map_err(|e| format!("{}: {e}", self.urdf.display()))?;
        let names: Vec<String> = robot
            .links
            .iter()
            .map(|l| urdf.links[l.urdf_link_index].name.clone())
            .collect();
        let physics = &mut world.physics;
        let handles = robot.insert_using_impulse_joints(
            &mut physics.bodies,
            &mut physics.colliders,
            &mut physics.impulse_joints,
        );
        let link = |name: &str| {
            names
                .iter()
                .position(|n| n == name)
                .map(|i| &handles.links[i])
                .ok_or_else(|| format!("no link {name} in {}", self.urdf.display()))
        };

        // Every link that a joint moves becomes kinematic. The joints driven here are prismatic
        // or fixed and their frames unturned, so a link's offset from where it was built is the
        // sum of its prismatic ancestors' displacements along their axes.
        let mut chains = Vec::new();
        for (name, l) in names.iter().zip(&handles.links) {
            let mut chain = Vec::new();
            let mut child = name.as_str();
            // A chain longer than the joints would be a cycle.
            for _ in 0..=urdf.joints.len() {
                let Some(j) = urdf.joints.iter().find(|j| j.child.link == child) else {
                    break;
                };
                if j.origin.rpy.iter().any(|a| *a != 0.0) {
                    return Err(format!(
                        "joint {}: a turned frame is not driven here",
                        j.name
                    ));
                }
                match &j.joint_type {
                    urdf_rs::JointType::Prismatic => {
                        let a = j.axis.xyz;
                        let axis = Vector::new(a[0] as Real, a[1] as Real, a[2] as Real);
                        chain.push((j.name.clone(), turn * axis));
                    }
                    urdf_rs::JointType::Fixed => {}
                    other => return Err(format!("joint {}: {other:?} is not driven here", j.name)),
                }
                child = &j.parent.link;
            }
            if !chain.is_empty() {
                let body = &mut world.physics.bodies[l.body];
                body.set_body_type(RigidBodyType::KinematicPositionBased, true);
                chains.push(Chain {
                    body: l.body,
                    built: body.translation(),
                    joints: chain,
                });
            }
        }

        // Each pad link's collision shape becomes a soft pad, bound to its finger where it
        // touches it; the rigid shape it replaces goes.
        let mut pads = Vec::new();
        for side in ["left", "right"] {
            let collider = |name: String| {
                let c = link(&name)?.colliders.first();
                c.map(|c| c.handle)
                    .ok_or_else(|| format!("link {name} has no collision shape"))
            };
            let pad_collider = collider(format!("{side}_pad"))?;
            let finger_collider = collider(format!("{side}_finger"))?;
            let (shape, pose) = {
                let c = &world.physics.colliders[pad_collider];
                (c.shared_shape().clone(), *c.position())
            };
            let mesh = Mesh::stuffed(shape.as_ref(), self.cell).map_err(|e| e.to_string())?;
            let body = DeformableBuilder::new(mesh)
                .model(self.model)
                .material(self.material)
                .translation(pose.translation)
                .rotation(pose.rotation)
                .friction(self.friction)
                .restitution(0.0)
                .build()
                .map_err(|e| e.to_string())?;
            let (nodes, cells) = (body.num_nodes(), body.mesh().num_cells());
            let handle = world.insert(body);
            world.physics.remove_collider(pad_collider);
            let bound = world
                .attach_nodes_inside(handle, finger_collider, 1e-3)
                .map_err(|e| e.to_string())?;
            pads.push(Pad {
                handle,
                nodes,
                cells,
                bound,
            });
        }
        let finger = link("left_finger")?.body;
        Ok(Gripper {
            world,
            box_body,
            pads,
            finger,
            chains,
            scene: self.clone(),
            steps: 0,
        })
    }

    /// Runs the scene, calling `observe` after every step with the world and the fraction done.
    pub fn run_with(
        &self,
        mut observe: impl FnMut(&DeformableWorld, f64),
    ) -> Result<GripperRecord, String> {
        let mut g = self.build()?;
        let total: Real = self.timeline.iter().sum();
        let steps = (total / self.dt).round() as usize;
        let lift_from = self.timeline[0] + self.timeline[1];
        let mut offset0 = None;
        let (mut slip, mut lowest): (Real, Real) = (0.0, Real::INFINITY);
        let mut step_seconds = Vec::with_capacity(steps);
        for k in 0..steps {
            step_seconds.push(g.step());
            observe(&g.world, (k + 1) as f64 / steps as f64);
            let height = g.box_bottom();
            lowest = lowest.min(height);
            if g.time() >= lift_from {
                let offset = height - g.world.physics.bodies[g.finger].translation().y;
                let o0 = *offset0.get_or_insert(offset);
                slip = slip.max((offset - o0).abs());
            }
        }
        Ok(GripperRecord {
            pads: g.pads.clone(),
            lifted: g.box_bottom(),
            slip,
            lowest,
            step_seconds,
        })
    }
}

impl Gripper {
    /// Time since the start, s.
    pub fn time(&self) -> Real {
        self.steps as Real * self.scene.dt
    }

    /// The box's bottom above the table, m.
    pub fn box_bottom(&self) -> Real {
        self.world.physics.bodies[self.box_body].translation().y - BOX_HALF
    }

    /// Places the links at the joints' targets for the end of the step and steps the world;
    /// returns the step's wall time, s.
    pub fn step(&mut self) -> f64 {
        let s = &self.scene;
        let t = (self.steps + 1) as Real * s.dt;
        let ramp = |start: Real, length: Real| {
            let u = ((t - start) / length).clamp(0.0, 1.0);
            u * u * (3.0 - 2.0 * u)
        };
        let [settle, close, lift, _] = s.timeline;
        let closed = ramp(settle, close) * s.close;
        let lifted = ramp(settle + close, lift) * s.lift;
        for c in &self.chains {
            let at = c.joints.iter().fold(c.built, |at, (joint, axis)| {
                let q = match joint.as_str() {
                    "lift" => lifted,
                    "left_slide" | "right_slide" => closed,
                    _ => 0.0,
                };
                at + *axis * q
            });
            self.world.physics.bodies[c.body].set_next_kinematic_translation(at);
        }
        let started = Instant::now();
        self.world.step();
        self.steps += 1;
        started.elapsed().as_secs_f64()
    }
}
