//! The particles' lifecycle in the DEM: neighbour-list rebuilds, particles that leave the
//! domain, particles inserted at the inlet, and the check that no particle has escaped.

use rand::Rng;

use super::*;

impl Dem {
    /// Conservative bounds (x_lo, x_hi, z_lo, z_hi) outside which a particle centre may have
    /// left the domain; [`Self::check_positions`] decides exactly.
    pub(super) fn escape_bounds(&self) -> (f64, f64, f64, f64) {
        let g = &self.setup.geometry;
        let r = self.setup.diameters.max() / 2.0;
        let height = g.z_hi - g.z_lo;
        let z_lo = if g.outlet_z.is_none() { g.z_lo - r } else { f64::NEG_INFINITY };
        (g.x_lo - r, g.x_hi + r, z_lo, g.z_hi + height)
    }

    pub(super) fn check_positions(&self) -> Result<()> {
        let g = &self.setup.geometry;
        let height = g.z_hi - g.z_lo;
        for i in 0..self.p.len() {
            let x = self.p.pos[i];
            let r = self.p.radius[i];
            let bad = if x.iter().any(|c| !c.is_finite()) {
                Some("its position is not finite")
            } else if x[0] < g.x_lo - r || x[0] > g.x_hi + r {
                Some("it left the domain through a side wall")
            } else if x[2] > g.z_hi + height || (g.outlet_z.is_none() && x[2] < g.z_lo - r) {
                Some("it left the domain vertically")
            } else {
                None
            };
            if let Some(why) = bad {
                return Err(Error::numerical(
                    "DEM",
                    format!(
                        "blow-up at step {} (t = {:.6e} s): particle {} at ({:.4e}, {:.4e}, {:.4e}) m, velocity {:?} m/s: {why}; lower the time step or raise the modulus",
                        self.step, self.time, self.p.id[i], x[0], x[1], x[2], self.p.vel[i]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Removes exited particles, inserts due ones, sorts by cell and rebuilds the half list,
    /// carrying pair histories over by particle id.
    pub(super) fn rebuild(&mut self) -> Result<()> {
        // Old index of every particle after removal and insertion (u32::MAX: new), so that the
        // histories of touching pairs can be carried over from the old list.
        let n_old = self.p.len();
        let mut origin: Vec<u32> = match self.remove_exited() {
            Some(keep) => keep,
            None => (0..n_old as u32).collect(),
        };
        self.insert_due();
        origin.resize(self.p.len(), u32::MAX);
        // Free wall slots whose wall is no longer touched.
        let g = &self.setup.geometry;
        let p = &mut self.p;
        p.walls.par_iter_mut().zip(p.pos.par_iter().zip(p.radius.par_iter())).with_min_len(BLOCK).for_each(|(slots, (&x, &r))| {
            for slot in slots.iter_mut() {
                if slot.wall != u32::MAX && wall_contact(g, slot.wall, x, r).is_none() {
                    *slot = WallSlot::FREE;
                }
            }
        });
        let (order, cell_of, cell_start) = sort_by_cell(&self.grid, &self.p.pos);
        self.p.gather(&order);
        let origin: Vec<u32> = order.iter().map(|&k| origin[k as usize]).collect();
        let slab = self.setup.geometry.slab;
        let (start, j) = build_pairs(&self.grid, &self.p.pos, &self.p.radius, &cell_of, &cell_start, self.setup.skin(), slab);
        let old = std::mem::take(&mut self.nl);
        let p = &self.p;
        let epoch = self.epoch;
        // Rows in parallel: only overlapping pairs look their history up (binary search in the
        // old row of the lower old index; rows are sorted).
        let state: Vec<PairState> = (0..p.len())
            .into_par_iter()
            .with_min_len(BLOCK)
            .flat_map_iter(|i| {
                let (old, origin, start, j) = (&old, &origin, &start, &j);
                (start[i] as usize..start[i + 1] as usize).map(move |k| {
                    let jj = j[k] as usize;
                    let (oi, oj) = (origin[i], origin[jj]);
                    if oi == u32::MAX || oj == u32::MAX || old.start.is_empty() {
                        return PairState::default();
                    }
                    let mut d = sub(p.pos[i], p.pos[jj]);
                    d[1] = min_image(d[1], slab);
                    let rs = p.radius[i] + p.radius[jj];
                    if dot(d, d) >= rs * rs {
                        return PairState::default();
                    }
                    let (a, b, sign) = if oi < oj { (oi, oj, 1.0) } else { (oj, oi, -1.0) };
                    // Particles placed by hand since the last build have no row.
                    if a as usize + 1 >= old.start.len() {
                        return PairState::default();
                    }
                    let row = &old.j[old.start[a as usize] as usize..old.start[a as usize + 1] as usize];
                    match row.binary_search(&b) {
                        Ok(pos) => {
                            let st = old.state[old.start[a as usize] as usize + pos];
                            if st.last == epoch && epoch > 0 { PairState { xi: scale(st.xi, sign), last: epoch } } else { PairState::default() }
                        }
                        Err(_) => PairState::default(),
                    }
                })
            })
            .collect();
        self.nl = NeighbourList { start, j, state, cell_of };
        self.p.pos_at_build.clone_from(&self.p.pos);
        self.steps_since_build = 0;
        self.counters.builds += 1;
        Ok(())
    }

    /// Removes particles below the outlet; returns the kept old indices when any left.
    pub(super) fn remove_exited(&mut self) -> Option<Vec<u32>> {
        let z_out = self.setup.geometry.outlet_z?;
        if !self.p.pos.iter().any(|x| x[2] < z_out) {
            return None;
        }
        let warm = self.setup.probes.warmup;
        let mut keep = Vec::with_capacity(self.p.len());
        for i in 0..self.p.len() {
            if self.p.pos[i][2] < z_out {
                self.outflow_mass += self.p.mass[i];
                self.counters.exited += 1;
                if self.time >= warm {
                    self.outflow_mass_measured += self.p.mass[i];
                }
                if self.time >= warm {
                    self.passes.push(Pass {
                        particle: self.p.id[i],
                        diameter: 2.0 * self.p.radius[i],
                        residence: self.time - self.p.t_insert[i],
                        tube_impacts: self.p.n_tube[i],
                        particle_impacts: self.p.n_particle[i],
                    });
                }
            } else {
                keep.push(i as u32);
            }
        }
        self.p.gather(&keep);
        Some(keep)
    }

    pub(super) fn insert_due(&mut self) {
        let Some(inlet) = self.setup.inlet else { return };
        let g = &self.setup.geometry;
        let area = (g.x_hi - g.x_lo) * g.slab;
        let target = inlet.mass_flux * area * self.time;
        let rho = self.setup.particle.density;
        let mass_of = |d: f64| rho * std::f64::consts::PI / 6.0 * d.powi(3);
        if self.inflow_mass + mass_of(self.next_diameter) > target {
            return;
        }
        let r_max = self.setup.diameters.max() / 2.0;
        // Particles that may overlap new ones.
        // Sorted by x: a candidate is checked against the particles within 2 r_max in x only.
        let mut near: Vec<(V3, f64)> = (0..self.p.len())
            .filter(|&i| self.p.pos[i][2] + self.p.radius[i] > inlet.z_lo - r_max)
            .map(|i| (self.p.pos[i], self.p.radius[i]))
            .collect();
        near.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]));
        let slab = g.slab;
        while self.inflow_mass + mass_of(self.next_diameter) <= target {
            let d = self.next_diameter;
            let r = d / 2.0;
            let mut placed = None;
            for _ in 0..50 {
                let x = [
                    self.rng.random_range(g.x_lo + r..g.x_hi - r),
                    self.rng.random_range(0.0..slab),
                    self.rng.random_range(inlet.z_lo + r..inlet.z_hi - r),
                ];
                let from = near.partition_point(|q| q.0[0] < x[0] - r - r_max);
                let to = near.partition_point(|q| q.0[0] <= x[0] + r + r_max);
                let free = near[from..to].iter().all(|&(y, ry)| {
                    let mut dy = x[1] - y[1];
                    dy = min_image(dy, slab);
                    (x[0] - y[0]).powi(2) + dy * dy + (x[2] - y[2]).powi(2) >= (r + ry).powi(2)
                });
                if free {
                    placed = Some(x);
                    break;
                }
            }
            let Some(x) = placed else {
                self.counters.deferred_insertions += 1;
                break;
            };
            let id = self.next_id;
            self.next_id += 1;
            self.p.push(id, x, [0.0, 0.0, -inlet.velocity], r, rho, self.setup.rotation, self.time);
            let at = near.partition_point(|q| q.0[0] < x[0]);
            near.insert(at, (x, r));
            self.inflow_mass += mass_of(d);
            self.counters.inserted += 1;
            self.next_diameter = self.setup.diameters.sample(&mut self.rng);
        }
    }
}
