//! What a DEM run measures: every impact at first contact, the mean vertical-velocity profile
//! and the (x, z) map of mean speed, hold-up and outlet mass flow, per-particle impact counts
//! per pass, and the force history of one traced tube impact.

/// What a particle hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Another particle.
    Particle,
    /// A tube.
    Tube,
    /// A plane wall (side walls, floors).
    Wall,
}

impl Target {
    /// Name used in tables.
    pub fn name(self) -> &'static str {
        match self {
            Target::Particle => "particle",
            Target::Tube => "tube",
            Target::Wall => "wall",
        }
    }
}

/// One impact, at the first step of a contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Time (s).
    pub time: f64,
    /// What was hit.
    pub target: Target,
    /// Particle id (for particle–particle impacts the lower index of the pair in storage).
    pub particle: u64,
    /// Partner particle id, or the wall id.
    pub partner: u64,
    /// Tube row hit (tube impacts) or row band of the contact point (others); 0 above the bank,
    /// rows + 1 below.
    pub row: u32,
    /// Diameter of the particle (m).
    pub diameter: f64,
    /// Normal approach speed at first contact (m/s, > 0 when approaching).
    pub v_normal: f64,
    /// Tangential relative speed at first contact (m/s).
    pub v_tangential: f64,
    /// Contact point (m).
    pub point: [f64; 3],
}

/// One particle's pass through the domain, from insertion to the outlet (recorded when it
/// leaves after the warm-up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pass {
    /// Particle id.
    pub particle: u64,
    /// Diameter (m).
    pub diameter: f64,
    /// Residence time (s).
    pub residence: f64,
    /// Tube impacts during the pass.
    pub tube_impacts: u32,
    /// Particle impacts during the pass.
    pub particle_impacts: u32,
}

/// A sample of the traced contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceSample {
    /// Time since the first contact step (s).
    pub time: f64,
    /// Overlap (m).
    pub overlap: f64,
    /// Normal force (N).
    pub normal_force: f64,
}

/// Accumulated field statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct Fields {
    /// z bins of the profile.
    pub z_edges: Vec<f64>,
    /// Σ v_z per z bin.
    pub sum_vz: Vec<f64>,
    /// Particle samples per z bin.
    pub count_z: Vec<u64>,
    /// x bins of the map.
    pub map_x_edges: Vec<f64>,
    /// z bins of the map.
    pub map_z_edges: Vec<f64>,
    /// Σ |v| per map cell (row-major, z outer).
    pub sum_speed: Vec<f64>,
    /// Σ v_z per map cell.
    pub sum_map_vz: Vec<f64>,
    /// Samples per map cell.
    pub count_map: Vec<u64>,
    /// Number of sampling instants.
    pub samples: u64,
}

impl Fields {
    /// Empty accumulators over [x_lo, x_hi] × [z_lo, z_hi].
    pub fn new(x: (f64, f64), z: (f64, f64), profile_bins: usize, map_nx: usize, map_nz: usize) -> Self {
        let edges = |lo: f64, hi: f64, n: usize| (0..=n).map(|k| lo + (hi - lo) * k as f64 / n as f64).collect::<Vec<_>>();
        Fields {
            z_edges: edges(z.0, z.1, profile_bins),
            sum_vz: vec![0.0; profile_bins],
            count_z: vec![0; profile_bins],
            map_x_edges: edges(x.0, x.1, map_nx),
            map_z_edges: edges(z.0, z.1, map_nz),
            sum_speed: vec![0.0; map_nx * map_nz],
            sum_map_vz: vec![0.0; map_nx * map_nz],
            count_map: vec![0; map_nx * map_nz],
            samples: 0,
        }
    }

    fn bin(edges: &[f64], v: f64) -> Option<usize> {
        let n = edges.len() - 1;
        let (lo, hi) = (edges[0], edges[n]);
        if !(v >= lo && v < hi) {
            return None;
        }
        Some((((v - lo) / (hi - lo) * n as f64) as usize).min(n - 1))
    }

    /// Adds one particle sample.
    #[inline]
    pub fn add(&mut self, pos: [f64; 3], vel: [f64; 3]) {
        if let Some(k) = Self::bin(&self.z_edges, pos[2]) {
            self.sum_vz[k] += vel[2];
            self.count_z[k] += 1;
        }
        if let (Some(ix), Some(iz)) = (Self::bin(&self.map_x_edges, pos[0]), Self::bin(&self.map_z_edges, pos[2])) {
            let c = iz * (self.map_x_edges.len() - 1) + ix;
            self.sum_speed[c] += (vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]).sqrt();
            self.sum_map_vz[c] += vel[2];
            self.count_map[c] += 1;
        }
    }

    /// Mean v_z per z bin (NaN where empty), with bin centres.
    pub fn profile(&self) -> Vec<(f64, f64, u64)> {
        (0..self.sum_vz.len())
            .map(|k| {
                let zc = 0.5 * (self.z_edges[k] + self.z_edges[k + 1]);
                let c = self.count_z[k];
                (zc, if c > 0 { self.sum_vz[k] / c as f64 } else { f64::NAN }, c)
            })
            .collect()
    }
}

/// Hold-up and outlet flow over time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowSample {
    /// Time (s).
    pub time: f64,
    /// Particles in the domain.
    pub particles: usize,
    /// Their mass (kg).
    pub mass: f64,
    /// Mass that has left through the outlet since the start (kg).
    pub outflow_mass: f64,
    /// Mass inserted since the start (kg).
    pub inflow_mass: f64,
}

/// Quantile of a sample by linear interpolation between order statistics (NaN if empty).
pub fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (values.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    values[lo] + (values[hi] - values[lo]) * (pos - lo as f64)
}
