//! Particle storage as a structure of arrays: one vector per field, all in the same order (the
//! neighbour-list build reorders them by cell for locality).

use super::vec3::V3;

/// Most walls (planes + tubes) one particle can touch at once.
pub const MAX_WALL_CONTACTS: usize = 4;

/// Tangential history of one particle–wall contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallSlot {
    /// Wall id (`u32::MAX` = free slot).
    pub wall: u32,
    /// Tangential displacement ξ (m).
    pub xi: V3,
}

impl WallSlot {
    /// A free slot.
    pub const FREE: WallSlot = WallSlot { wall: u32::MAX, xi: [0.0; 3] };
}

/// All particles.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Positions (m).
    pub pos: Vec<V3>,
    /// Velocities (m/s).
    pub vel: Vec<V3>,
    /// Angular velocities (rad/s).
    pub omega: Vec<V3>,
    /// Velocity predicted at the end of the step, v(t) + Δt a(t), seen by the contact damping.
    pub vel_pred: Vec<V3>,
    /// Angular velocity predicted likewise.
    pub omega_pred: Vec<V3>,
    /// Forces of the last evaluation (N).
    pub force: Vec<V3>,
    /// Torques of the last evaluation (N·m).
    pub torque: Vec<V3>,
    /// Radii (m).
    pub radius: Vec<f64>,
    /// Masses (kg).
    pub mass: Vec<f64>,
    /// 1 / (0.4 m r²) (1/(kg m²)); 0 when rotation is frozen.
    pub inv_inertia: Vec<f64>,
    /// Global ids (insertion order, never reused).
    pub id: Vec<u64>,
    /// Insertion times (s).
    pub t_insert: Vec<f64>,
    /// Tube impacts so far.
    pub n_tube: Vec<u32>,
    /// Particle impacts so far.
    pub n_particle: Vec<u32>,
    /// Position at the last neighbour-list build.
    pub pos_at_build: Vec<V3>,
    /// Wall-contact histories.
    pub walls: Vec<[WallSlot; MAX_WALL_CONTACTS]>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Appends a particle.
    #[allow(clippy::too_many_arguments)]
    pub fn push(&mut self, id: u64, pos: V3, vel: V3, radius: f64, density: f64, rotation: bool, t: f64) {
        let mass = density * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
        self.pos.push(pos);
        self.vel.push(vel);
        self.omega.push([0.0; 3]);
        self.vel_pred.push(vel);
        self.omega_pred.push([0.0; 3]);
        self.force.push([0.0; 3]);
        self.torque.push([0.0; 3]);
        self.radius.push(radius);
        self.mass.push(mass);
        self.inv_inertia.push(if rotation { 1.0 / (0.4 * mass * radius * radius) } else { 0.0 });
        self.id.push(id);
        self.t_insert.push(t);
        self.n_tube.push(0);
        self.n_particle.push(0);
        self.pos_at_build.push(pos);
        self.walls.push([WallSlot::FREE; MAX_WALL_CONTACTS]);
    }

    /// Makes `self` the particles of `src` in the order `order`: new index k holds `src`'s index
    /// `order[k]` (which may drop particles). The arrays keep their capacity, so a rebuild that
    /// gathers into the spare set and swaps allocates nothing, and the insertions that follow
    /// push without reallocating; the fields are gathered side by side (one task each).
    pub fn gather_from(&mut self, src: &Particles, order: &[u32]) {
        let Particles { pos, vel, omega, vel_pred, omega_pred, force, torque, radius, mass, inv_inertia, id, t_insert, n_tube, n_particle, pos_at_build, walls } = self;
        // (Defined after the binding: a macro's identifiers resolve where it is defined.)
        macro_rules! every_field {
            ($m:ident) => {
                $m!(pos);
                $m!(vel);
                $m!(omega);
                $m!(vel_pred);
                $m!(omega_pred);
                $m!(force);
                $m!(torque);
                $m!(radius);
                $m!(mass);
                $m!(inv_inertia);
                $m!(id);
                $m!(t_insert);
                $m!(n_tube);
                $m!(n_particle);
                $m!(pos_at_build);
                $m!(walls);
            };
        }
        // A small system is gathered on this thread: handing the fields out costs more.
        if order.len() < crate::model::pass_min_len(super::grid::PARALLEL_BLOCKS * super::grid::BLOCK) {
            macro_rules! field {
                ($dst:ident) => {
                    $dst.clear();
                    $dst.extend(order.iter().map(|&k| src.$dst[k as usize]));
                };
            }
            every_field!(field);
            return;
        }
        rayon::scope(|s| {
            macro_rules! field {
                ($dst:ident) => {
                    s.spawn(move |_| {
                        $dst.clear();
                        $dst.extend(order.iter().map(|&k| src.$dst[k as usize]));
                    });
                };
            }
            every_field!(field);
        });
    }

    /// Kinetic energy, translational + rotational (J).
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for i in 0..self.len() {
            let v = self.vel[i];
            e += 0.5 * self.mass[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if self.inv_inertia[i] > 0.0 {
                let w = self.omega[i];
                e += 0.5 * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / self.inv_inertia[i];
            }
        }
        e
    }
}
