//! The force kernels of the DEM step: minimum image, half kicks, wall contacts and the
//! per-block pair and wall force evaluation ([`Ctx`]).

use super::contact::{ContactGeom, PairLaw, contact_velocity, hertz_mindlin, tube_radius_star};
use super::geometry::Geometry;
use super::grid::{BLOCK, Grid, PairBlock};
use super::particles::{MAX_WALL_CONTACTS, WallSlot};
use super::probe::{Impact, Target, TraceSample};
use super::vec3::{V3, add_to, cross, dot, norm, scale, sub};
use super::BlockOut;

/// Minimum-image separation along the periodic axis.
#[inline(always)]
pub(super) fn min_image(d: f64, slab: f64) -> f64 {
    d - slab * (d / slab).round()
}

/// Half kick: v += a f, ω += b T (a = ½Δt/m, b = ½Δt/I).
#[inline(always)]
pub(super) fn kick(v: &mut V3, w: &mut V3, f: V3, t: V3, a: f64, b: f64) {
    for c in 0..3 {
        v[c] += a * f[c];
        w[c] += b * t[c];
    }
}

/// What the last step left for the next pass over the particles: the force pass's reactions
/// (bucketed per block, `reach` the largest block offset) and the closing half kick.
pub(super) struct Pending<'a> {
    pub(super) outs: &'a [BlockOut],
    pub(super) reach: usize,
    pub(super) reactions: bool,
    pub(super) close: bool,
    /// ½Δt.
    pub(super) half: f64,
}

impl Pending<'_> {
    /// Adds to block `b`'s forces and torques the reactions on its particles from every block up
    /// to and including it, in block order. The closing kick is then the caller's: the
    /// kick–drift pass applies it per particle with the opening kick's factors (one division by
    /// the mass for both), [`Pending::apply`] on its own.
    pub(super) fn add_reactions(&self, b: usize, fs: &mut [V3], ts: &mut [V3]) {
        if self.reactions {
            let lo = b * BLOCK;
            for s in b.saturating_sub(self.reach)..=b {
                if let Some(list) = self.outs.get(s).and_then(|o| o.reactions.get(b - s)) {
                    for &(j, f, t) in list {
                        add_to(&mut fs[j as usize - lo], f);
                        add_to(&mut ts[j as usize - lo], t);
                    }
                }
            }
        }
    }

    /// Applies it all to block `b`: the reactions, then the closing half kick with the complete
    /// forces.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply(&self, b: usize, vs: &mut [V3], ws: &mut [V3], fs: &mut [V3], ts: &mut [V3], ms: &[f64], iis: &[f64]) {
        self.add_reactions(b, fs, ts);
        if self.close {
            for k in 0..vs.len() {
                kick(&mut vs[k], &mut ws[k], fs[k], ts[k], self.half / ms[k], self.half * iis[k]);
            }
        }
    }
}

/// Contact of a sphere (centre x, radius r) with wall w: (overlap, normal into the particle,
/// R*, kind, tube row).
#[inline(always)]
pub(super) fn wall_contact(g: &Geometry, w: u32, x: V3, r: f64) -> Option<(f64, V3, f64, Target, u32)> {
    let w = w as usize;
    if w < g.planes.len() {
        let p = &g.planes[w];
        let delta = r - p.distance(x);
        if delta > 0.0 { Some((delta, p.normal, r, Target::Wall, 0)) } else { None }
    } else {
        let t = &g.tubes[w - g.planes.len()];
        let dx = x[0] - t.x;
        let dz = x[2] - t.z;
        let reach = r + t.radius;
        let d2 = dx * dx + dz * dz;
        if d2 >= reach * reach {
            return None;
        }
        let d = d2.sqrt();
        Some((reach - d, [dx / d, 0.0, dz / d], tube_radius_star(r, t.radius), Target::Tube, t.row))
    }
}

/// Read-only context of the force loop.
pub(super) struct Ctx<'a> {
    pub(super) pos: &'a [V3],
    pub(super) vel: &'a [V3],
    pub(super) omega: &'a [V3],
    pub(super) radius: &'a [f64],
    pub(super) mass: &'a [f64],
    pub(super) id: &'a [u64],
    pub(super) start: &'a [u32],
    pub(super) cell_of: &'a [u32],
    pub(super) grid: &'a Grid,
    pub(super) geom: &'a Geometry,
    pub(super) pp: &'a PairLaw,
    pub(super) pw: &'a PairLaw,
    pub(super) dt: f64,
    pub(super) time: f64,
    pub(super) gravity: V3,
    pub(super) min_v: f64,
    pub(super) max_overlap: f64,
    pub(super) trace: Option<(u64, u32)>,
    pub(super) epoch: u32,
}

impl Ctx<'_> {
    /// Forces on the particles of one block (starting at `lo`), records into `out` (cleared).
    pub(super) fn block(&self, lo: usize, force: &mut [V3], torque: &mut [V3], walls: &mut [[WallSlot; MAX_WALL_CONTACTS]], pairs: &mut PairBlock, out: &mut BlockOut) {
        for r in &mut out.reactions {
            r.clear();
        }
        let own_block = lo / BLOCK;
        out.impacts.clear();
        out.trace.clear();
        out.trace_ended = false;
        out.worst_overlap = None;
        let base = self.start[lo] as usize;
        let slab = self.geom.slab;
        let half = 0.5 * slab;
        for (li, ((f, t), slots)) in force.iter_mut().zip(torque.iter_mut()).zip(walls.iter_mut()).enumerate() {
            let i = lo + li;
            let (pi, vi, wi, ri, mi) = (self.pos[i], self.vel[i], self.omega[i], self.radius[i], self.mass[i]);
            let mut fi = scale(self.gravity, mi);
            let mut ti = [0.0; 3];
            for k in self.start[i] as usize..self.start[i + 1] as usize {
                let j = pairs.j[k - base] as usize;
                let pj = self.pos[j];
                let mut d = [pi[0] - pj[0], pi[1] - pj[1], pi[2] - pj[2]];
                if d[1] > half {
                    d[1] -= slab;
                } else if d[1] < -half {
                    d[1] += slab;
                }
                let rj = self.radius[j];
                let rs = ri + rj;
                let r2 = dot(d, d);
                if r2 >= rs * rs {
                    continue;
                }
                let st = &mut pairs.state[k - base];
                let new_contact = st.last + 1 != self.epoch;
                if new_contact {
                    st.xi = [0.0; 3];
                }
                st.last = self.epoch;
                let dist = r2.sqrt();
                let delta = rs - dist;
                let n = scale(d, 1.0 / dist);
                let v_rel = contact_velocity(vi, self.vel[j], wi, self.omega[j], ri, rj, n);
                let mj = self.mass[j];
                let c = ContactGeom {
                    n,
                    delta,
                    v_rel,
                    w_rel: sub(wi, self.omega[j]),
                    r_star: ri * rj / rs,
                    m_star: mi * mj / (mi + mj),
                };
                let cf = hertz_mindlin(self.pp, &c, &mut st.xi, self.dt);
                if delta > self.max_overlap * ri.min(rj) && out.worst_overlap.is_none_or(|w| delta / ri.min(rj) > w.0) {
                    out.worst_overlap = Some((delta / ri.min(rj), i as u32));
                }
                if new_contact {
                    let vn = -dot(v_rel, n);
                    if vn >= self.min_v {
                        let vt = norm(sub(v_rel, scale(n, -vn)));
                        let point = sub(pi, scale(n, ri - 0.5 * delta));
                        out.impacts.push((
                            Impact {
                                time: self.time,
                                target: Target::Particle,
                                particle: self.id[i],
                                partner: self.id[j],
                                row: self.geom.row_of(point[2]),
                                diameter: 2.0 * ri,
                                v_normal: vn,
                                v_tangential: vt,
                                point,
                            },
                            i as u32,
                            j as u32,
                            delta,
                            cf.normal,
                        ));
                    }
                }
                add_to(&mut fi, cf.force);
                let arm_x_f = cross(n, cf.force);
                add_to(&mut ti, scale(arm_x_f, -ri));
                add_to(&mut ti, cf.rolling_torque);
                let tj = sub(scale(arm_x_f, -rj), cf.rolling_torque);
                // Bucketed by the target's block, counted from this one (j > i: never before).
                let offset = j / BLOCK - own_block;
                if out.reactions.len() <= offset {
                    out.reactions.resize_with(offset + 1, Vec::new);
                }
                out.reactions[offset].push((j as u32, scale(cf.force, -1.0), tj));
            }
            // Walls and tubes near the particle's cell.
            for &w in self.grid.walls_near(self.cell_of[i] as usize) {
                let slot_k = slots.iter().position(|s| s.wall == w);
                let Some((delta, n, r_star, target, row)) = wall_contact(self.geom, w, pi, ri) else {
                    if let Some(k) = slot_k {
                        slots[k] = WallSlot::FREE;
                        if self.trace == Some((self.id[i], w)) {
                            out.trace.push(TraceSample { time: self.time, overlap: 0.0, normal_force: 0.0 });
                            out.trace_ended = true;
                        }
                    }
                    continue;
                };
                let (k, new) = match slot_k {
                    Some(k) => (Some(k), false),
                    None => (slots.iter().position(|s| s.wall == u32::MAX), true),
                };
                let mut scratch = [0.0; 3];
                let xi = match k {
                    Some(k) => {
                        slots[k].wall = w;
                        &mut slots[k].xi
                    }
                    None => &mut scratch,
                };
                let v_rel = contact_velocity(vi, [0.0; 3], wi, [0.0; 3], ri, 0.0, n);
                let c = ContactGeom { n, delta, v_rel, w_rel: wi, r_star, m_star: mi };
                let cf = hertz_mindlin(self.pw, &c, xi, self.dt);
                if delta > self.max_overlap * ri && out.worst_overlap.is_none_or(|x| delta / ri > x.0) {
                    out.worst_overlap = Some((delta / ri, i as u32));
                }
                add_to(&mut fi, cf.force);
                add_to(&mut ti, scale(cross(n, cf.force), -ri));
                add_to(&mut ti, cf.rolling_torque);
                if new {
                    let vn = -dot(v_rel, n);
                    if vn >= self.min_v {
                        let vt = norm(sub(v_rel, scale(n, -vn)));
                        let point = sub(pi, scale(n, ri - delta));
                        let row = if target == Target::Tube { row } else { self.geom.row_of(point[2]) };
                        out.impacts.push((
                            Impact {
                                time: self.time,
                                target,
                                particle: self.id[i],
                                partner: w as u64,
                                row,
                                diameter: 2.0 * ri,
                                v_normal: vn,
                                v_tangential: vt,
                                point,
                            },
                            i as u32,
                            u32::MAX,
                            delta,
                            cf.normal,
                        ));
                    }
                } else if self.trace == Some((self.id[i], w)) {
                    out.trace.push(TraceSample { time: self.time, overlap: delta, normal_force: cf.normal });
                }
            }
            *f = fi;
            *t = ti;
        }
    }
}
