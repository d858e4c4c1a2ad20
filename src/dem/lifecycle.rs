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
    /// carrying pair histories over by particle index. The exited particles are left out by the
    /// sort, so the particle arrays are gathered once.
    pub(super) fn rebuild(&mut self) -> Result<()> {
        let n_old = self.p.len();
        let exited = self.record_exits();
        self.insert_due(exited.as_deref());
        // Free wall slots whose wall is no longer touched.
        let g = &self.setup.geometry;
        let p = &mut self.p;
        p.walls.par_iter_mut().zip(p.pos.par_iter().zip(p.radius.par_iter())).with_min_len(crate::model::pass_min_len(PARALLEL_BLOCKS * BLOCK)).for_each(|(slots, (&x, &r))| {
            for slot in slots.iter_mut() {
                if slot.wall != u32::MAX && wall_contact(g, slot.wall, x, r).is_none() {
                    *slot = WallSlot::FREE;
                }
            }
        });
        let mut buf = std::mem::take(&mut self.cell_buf);
        let (order, cell_of, cell_start) = sort_by_cell(&self.grid, &self.p.pos, exited.as_deref(), &mut buf);
        self.spare.gather_from(&self.p, &order);
        std::mem::swap(&mut self.p, &mut self.spare);
        // Index in the old list of each sorted particle (inserted ones have none).
        let origin: Vec<u32> = order.iter().map(|&k| if (k as usize) < n_old { k } else { u32::MAX }).collect();
        let old = std::mem::take(&mut self.nl);
        let history = History { old: &old, origin: &origin, epoch: self.epoch };
        self.nl = NeighbourList::build(&self.grid, &self.p.pos, &self.p.radius, cell_of, cell_start, self.setup.skin(), self.setup.geometry.slab, &history);
        self.cell_buf = buf;
        self.p.pos_at_build.clone_from(&self.p.pos);
        self.steps_since_build = 0;
        self.counters.builds += 1;
        Ok(())
    }

    /// Records the particles below the outlet (outflow, passes after the warm-up); returns which
    /// particles left when any did. They stay in the arrays until the rebuild's sort drops them.
    pub(super) fn record_exits(&mut self) -> Option<Vec<bool>> {
        let z_out = self.setup.geometry.outlet_z?;
        if !self.p.pos.iter().any(|x| x[2] < z_out) {
            return None;
        }
        let warm = self.setup.probes.warmup;
        let mut gone = vec![false; self.p.len()];
        for (i, out) in gone.iter_mut().enumerate() {
            if self.p.pos[i][2] < z_out {
                *out = true;
                self.outflow_mass += self.p.mass[i];
                self.counters.exited += 1;
                if self.time >= warm {
                    self.outflow_mass_measured += self.p.mass[i];
                    self.passes.push(Pass {
                        particle: self.p.id[i],
                        diameter: 2.0 * self.p.radius[i],
                        residence: self.time - self.p.t_insert[i],
                        tube_impacts: self.p.n_tube[i],
                        particle_impacts: self.p.n_particle[i],
                    });
                }
            }
        }
        Some(gone)
    }

    /// Inserts the particles due at the inlet, clear of every particle not marked `gone`.
    pub(super) fn insert_due(&mut self, gone: Option<&[bool]>) {
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
            .filter(|&i| self.p.pos[i][2] + self.p.radius[i] > inlet.z_lo - r_max && !gone.is_some_and(|g| g[i]))
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
