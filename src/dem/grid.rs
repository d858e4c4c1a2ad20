//! Neighbour search: a uniform cell grid (periodic along y) with sorted cells, and a Verlet
//! half neighbour list (pairs i < j within r_i + r_j + skin) rebuilt when any particle has moved
//! more than half the skin since the last build.
//!
//! A rebuild: the particles' cells in parallel and a counting sort over the occupied span of
//! cells ([`sort_by_cell`]); the particle arrays gathered into that order; then one parallel pass
//! over fixed blocks of [`BLOCK`] particles that finds each row's pairs and carries the contact
//! history of touching pairs over from the previous list ([`NeighbourList::build`]). Each block
//! keeps its own pair storage ([`PairBlock`]), the same blocks the force loop owns, so nothing is
//! concatenated serially.
//!
//! The grid also keeps, per cell, the walls (planes and tubes) within reach of a particle in
//! that cell, so the wall loop tests a handful of candidates instead of every tube.

use rayon::prelude::*;

use super::geometry::Geometry;
use super::vec3::V3;

/// Particles per block of the neighbour list and the force loop (fixed: results do not depend on
/// the thread count).
pub const BLOCK: usize = 256;

/// Below this many blocks a pass runs as one task: handing a block of a few microseconds' work
/// to another thread costs about as much as doing it (small rigs, or many runs side by side).
pub const PARALLEL_BLOCKS: usize = 8;

/// Blocks per task of a pass over `nblocks` blocks: all of them below [`PARALLEL_BLOCKS`] or
/// inside one run of a batch that keeps every thread busy ([`crate::model::pass_min_len`]),
/// else one (each block a task, for balance where the contact density varies with height).
#[inline]
pub fn blocks_per_task(nblocks: usize) -> usize {
    if nblocks < PARALLEL_BLOCKS || crate::model::in_full_batch() { nblocks.max(1) } else { 1 }
}

/// The cell grid.
#[derive(Debug, Clone)]
pub struct Grid {
    x_lo: f64,
    z_lo: f64,
    cell_x: f64,
    cell_y: f64,
    cell_z: f64,
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Cells along z.
    pub nz: usize,
    slab: f64,
    wall_start: Vec<u32>,
    wall_ids: Vec<u32>,
    /// Distinct neighbour-cell offsets along y (−1, 0, 1, deduplicated when ny < 3).
    y_offsets: Vec<isize>,
    /// Per cell, its neighbour cells with an index ≥ its own, sorted (CSR): particles are sorted
    /// by cell, so these hold exactly the candidates j > i of a half list, in increasing order.
    fwd_start: Vec<u32>,
    fwd_cells: Vec<u32>,
}

impl Grid {
    /// A grid of cells at least `cutoff` wide over the geometry, with wall candidates within
    /// `wall_margin` of each cell.
    pub fn new(g: &Geometry, cutoff: f64, wall_margin: f64) -> Self {
        // The grid extends a cutoff beyond the domain in z so that particles just leaving
        // through the outlet or inserted at the top are still binned exactly.
        let z_lo = g.z_lo - 2.0 * cutoff;
        let z_hi = g.z_hi + 2.0 * cutoff;
        let nx = (((g.x_hi - g.x_lo) / cutoff).floor() as usize).max(1);
        let ny = ((g.slab / cutoff).floor() as usize).max(1);
        let nz = (((z_hi - z_lo) / cutoff).floor() as usize).max(1);
        let cell_x = (g.x_hi - g.x_lo) / nx as f64;
        let cell_y = g.slab / ny as f64;
        let cell_z = (z_hi - z_lo) / nz as f64;
        let mut y_offsets: Vec<isize> = vec![-1, 0, 1];
        if ny < 3 {
            y_offsets = if ny == 1 { vec![0] } else { vec![0, 1] };
        }
        let mut grid = Grid {
            x_lo: g.x_lo,
            z_lo,
            cell_x,
            cell_y,
            cell_z,
            nx,
            ny,
            nz,
            slab: g.slab,
            wall_start: Vec::new(),
            wall_ids: Vec::new(),
            y_offsets,
            fwd_start: Vec::new(),
            fwd_cells: Vec::new(),
        };
        grid.build_wall_candidates(g, wall_margin);
        let mut start = Vec::with_capacity(grid.cells() + 1);
        let mut cells = Vec::new();
        let mut tmp = Vec::with_capacity(27);
        start.push(0u32);
        for c in 0..grid.cells() {
            let cz = c / (nx * ny);
            let cy = (c / nx) % ny;
            let cx = c % nx;
            grid.neighbour_cells((cx, cy, cz), &mut tmp);
            tmp.retain(|&n| n >= c);
            tmp.sort_unstable();
            cells.extend(tmp.iter().map(|&n| n as u32));
            start.push(cells.len() as u32);
        }
        grid.fwd_start = start;
        grid.fwd_cells = cells;
        grid
    }

    fn build_wall_candidates(&mut self, g: &Geometry, margin: f64) {
        let (hx, hy, hz) = (self.cell_x / 2.0, self.cell_y / 2.0, self.cell_z / 2.0);
        let mut start = Vec::with_capacity(self.cells() + 1);
        let mut ids = Vec::new();
        start.push(0u32);
        for cz in 0..self.nz {
            for cy in 0..self.ny {
                for cx in 0..self.nx {
                    let c = [
                        self.x_lo + (cx as f64 + 0.5) * self.cell_x,
                        (cy as f64 + 0.5) * self.cell_y,
                        self.z_lo + (cz as f64 + 0.5) * self.cell_z,
                    ];
                    for (w, p) in g.planes.iter().enumerate() {
                        let reach = p.normal[0].abs() * hx + p.normal[1].abs() * hy + p.normal[2].abs() * hz;
                        if p.distance(c) - reach < margin {
                            ids.push(w as u32);
                        }
                    }
                    for (t, tube) in g.tubes.iter().enumerate() {
                        let dx = ((c[0] - tube.x).abs() - hx).max(0.0);
                        let dz = ((c[2] - tube.z).abs() - hz).max(0.0);
                        if (dx * dx + dz * dz).sqrt() - tube.radius < margin {
                            ids.push((g.planes.len() + t) as u32);
                        }
                    }
                    start.push(ids.len() as u32);
                }
            }
        }
        self.wall_start = start;
        self.wall_ids = ids;
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Cell coordinates of a position (clamped in x and z, wrapped in y).
    #[inline]
    pub fn coords(&self, p: V3) -> (usize, usize, usize) {
        let cx = (((p[0] - self.x_lo) / self.cell_x).floor().max(0.0) as usize).min(self.nx - 1);
        let yw = p[1] - self.slab * (p[1] / self.slab).floor();
        let cy = ((yw / self.cell_y).floor().max(0.0) as usize).min(self.ny - 1);
        let cz = (((p[2] - self.z_lo) / self.cell_z).floor().max(0.0) as usize).min(self.nz - 1);
        (cx, cy, cz)
    }

    /// Linear cell index.
    #[inline]
    pub fn index(&self, c: (usize, usize, usize)) -> usize {
        (c.2 * self.ny + c.1) * self.nx + c.0
    }

    /// Wall ids within reach of a particle binned in cell `cell`.
    #[inline]
    pub fn walls_near(&self, cell: usize) -> &[u32] {
        &self.wall_ids[self.wall_start[cell] as usize..self.wall_start[cell + 1] as usize]
    }

    /// Neighbour cells with an index ≥ `cell`, sorted.
    #[inline]
    pub fn forward_cells(&self, cell: usize) -> &[u32] {
        &self.fwd_cells[self.fwd_start[cell] as usize..self.fwd_start[cell + 1] as usize]
    }

    /// The distinct neighbour cells of a cell (itself included).
    pub fn neighbour_cells(&self, c: (usize, usize, usize), out: &mut Vec<usize>) {
        out.clear();
        for dz in -1isize..=1 {
            let z = c.2 as isize + dz;
            if z < 0 || z >= self.nz as isize {
                continue;
            }
            for &dy in &self.y_offsets {
                let y = (c.1 as isize + dy).rem_euclid(self.ny as isize);
                for dx in -1isize..=1 {
                    let x = c.0 as isize + dx;
                    if x < 0 || x >= self.nx as isize {
                        continue;
                    }
                    out.push(self.index((x as usize, y as usize, z as usize)));
                }
            }
        }
    }
}

/// State of one neighbour pair.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairState {
    /// Tangential displacement ξ, oriented for the pair's (i, j) order.
    pub xi: V3,
    /// Force evaluation (epoch, ≥ 1) at which the pair last touched; 0 = never. A pair touching
    /// now continues a contact when it touched at the previous evaluation, so separated pairs
    /// need no write (and the force loop reads no state for pairs not in contact).
    pub last: u32,
}

/// The rows of one block of [`BLOCK`] particles: neighbour indices j > i and their pair states,
/// row after row.
#[derive(Debug, Clone, Default)]
pub struct PairBlock {
    /// Neighbour indices, rows in particle order, each sorted.
    pub j: Vec<u32>,
    /// Pair states, aligned with `j`.
    pub state: Vec<PairState>,
}

/// Half neighbour list: global row starts (CSR) and the pairs stored per block.
#[derive(Debug, Clone, Default)]
pub struct NeighbourList {
    /// Row starts, len n + 1 (global pair numbering).
    pub start: Vec<u32>,
    /// Pairs of particles [b·BLOCK, (b+1)·BLOCK).
    pub blocks: Vec<PairBlock>,
    /// Cell of each particle at the build.
    pub cell_of: Vec<u32>,
}

/// What a rebuild carries over: the previous list, each particle's index in it
/// (`u32::MAX` = inserted since) and the force evaluation that list last saw.
pub struct History<'a> {
    /// The previous list.
    pub old: &'a NeighbourList,
    /// Index in the previous list of each (sorted) particle.
    pub origin: &'a [u32],
    /// The last force evaluation (epoch).
    pub epoch: u32,
}

impl History<'_> {
    /// The state of touching pair (i, j) in the previous list, oriented for (i, j); a fresh state
    /// when either particle is new or the pair did not touch at the last evaluation.
    fn carry(&self, i: usize, j: usize) -> PairState {
        let (oi, oj) = (self.origin[i], self.origin[j]);
        let old = self.old;
        if oi == u32::MAX || oj == u32::MAX || old.start.is_empty() || self.epoch == 0 {
            return PairState::default();
        }
        let (a, b, sign) = if oi < oj { (oi, oj, 1.0) } else { (oj, oi, -1.0) };
        // Particles placed by hand since the last build have no row.
        if a as usize + 1 >= old.start.len() {
            return PairState::default();
        }
        let (row, states) = old.row(a as usize);
        match row.binary_search(&b) {
            Ok(pos) if states[pos].last == self.epoch => {
                let xi = states[pos].xi;
                PairState { xi: [sign * xi[0], sign * xi[1], sign * xi[2]], last: self.epoch }
            }
            _ => PairState::default(),
        }
    }
}

impl NeighbourList {
    /// Row i: its neighbours j > i and their states.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[PairState]) {
        let b = i / BLOCK;
        let base = self.start[b * BLOCK] as usize;
        let (s, e) = (self.start[i] as usize - base, self.start[i + 1] as usize - base);
        let blk = &self.blocks[b];
        (&blk.j[s..e], &blk.state[s..e])
    }

    /// The half list of particles already sorted by cell: j > i within r_i + r_j + skin (minimum
    /// image along y), with the history of pairs touching now carried over from `history`. One
    /// parallel pass over fixed blocks; the row starts are summed serially (one add a particle).
    #[allow(clippy::too_many_arguments)]
    pub fn build(grid: &Grid, pos: &[V3], radius: &[f64], cell_of: Vec<u32>, cells: CellStarts, skin: f64, slab: f64, history: &History) -> NeighbourList {
        let n = pos.len();
        let half = slab / 2.0;
        let nblocks = n.div_ceil(BLOCK);
        let per_task = blocks_per_task(nblocks);
        let built: Vec<(Vec<u32>, PairBlock)> = (0..nblocks)
            .into_par_iter()
            .with_min_len(per_task)
            .with_max_len(per_task)
            .map(|b| {
                let lo = b * BLOCK;
                let hi = (lo + BLOCK).min(n);
                let mut counts = Vec::with_capacity(hi - lo);
                let mut blk = PairBlock { j: Vec::with_capacity((hi - lo) * 8), state: Vec::with_capacity((hi - lo) * 8) };
                for i in lo..hi {
                    let before = blk.j.len();
                    let (pi, ri) = (pos[i], radius[i]);
                    // Forward cells in increasing order: rows come out sorted by j.
                    for &nc in grid.forward_cells(cell_of[i] as usize) {
                        let nc = nc as usize;
                        let (s, e) = cells.range(nc);
                        let s = s.max(i + 1);
                        for j in s..e {
                            let pj = pos[j];
                            let dx = pi[0] - pj[0];
                            let mut dy = pi[1] - pj[1];
                            if dy > half {
                                dy -= slab;
                            } else if dy < -half {
                                dy += slab;
                            }
                            let dz = pi[2] - pj[2];
                            let d2 = dx * dx + dy * dy + dz * dz;
                            let touch = ri + radius[j];
                            let cut = touch + skin;
                            if d2 < cut * cut {
                                blk.j.push(j as u32);
                                // Only pairs touching now look their history up.
                                blk.state.push(if d2 < touch * touch { history.carry(i, j) } else { PairState::default() });
                            }
                        }
                    }
                    counts.push((blk.j.len() - before) as u32);
                }
                (counts, blk)
            })
            .collect();
        let mut start = Vec::with_capacity(n + 1);
        start.push(0u32);
        let mut blocks = Vec::with_capacity(built.len());
        let mut last = 0u32;
        for (counts, blk) in built {
            for c in counts {
                last += c;
                start.push(last);
            }
            blocks.push(blk);
        }
        NeighbourList { start, blocks, cell_of }
    }
}

/// Where each cell's particles lie in the sorted order, for the cells from `base` on: cell c holds
/// `starts[c − base]..starts[c − base + 1]`; cells outside are empty.
#[derive(Debug, Clone, Copy)]
pub struct CellStarts<'b> {
    base: usize,
    starts: &'b [u32],
}

impl CellStarts<'_> {
    /// The sorted particles of cell `c`.
    #[inline]
    pub fn range(&self, c: usize) -> (usize, usize) {
        match c.checked_sub(self.base) {
            Some(k) if k + 1 < self.starts.len() => (self.starts[k] as usize, self.starts[k + 1] as usize),
            _ => (0, 0),
        }
    }
}

/// Sorts particles by cell, leaving out those `drop` marks (indices past its end are kept):
/// returns (order, cell of each sorted particle, where each cell's particles lie). The cells are
/// found in parallel; the counting sort is stable (equal cells keep their input order) and counts
/// only from the lowest occupied cell to the highest plus the reach of a cell's forward
/// neighbours (less than two layers of cells), so a large, sparse grid (a long incline, a wide
/// box) costs what its particles occupy. `buf` is the sort's array, kept by the caller.
pub fn sort_by_cell<'b>(grid: &Grid, pos: &[V3], drop: Option<&[bool]>, buf: &'b mut Vec<u32>) -> (Vec<u32>, Vec<u32>, CellStarts<'b>) {
    const GONE: u32 = u32::MAX;
    let cells: Vec<u32> = pos
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(i, &p)| if drop.is_some_and(|d| d.get(i).copied().unwrap_or(false)) { GONE } else { grid.index(grid.coords(p)) as u32 })
        .collect();
    let (lo, hi) = cells.iter().filter(|&&c| c != GONE).fold((usize::MAX, 0usize), |(lo, hi), &c| (lo.min(c as usize), hi.max(c as usize)));
    let base = if lo == usize::MAX { 0 } else { lo };
    // Forward neighbours of cell c lie in c ..= c + 2 nx ny (the next z layer, y wrapped).
    let top = if lo == usize::MAX { 0 } else { (hi + 2 * grid.nx * grid.ny + 1).min(grid.cells() - 1) };
    let nc = top + 1 - base;
    // buf[k + 1] counts cell base + k; its prefix sums make buf[k + 1] the end of that cell;
    // scattering from the last particle down then moves buf[k + 1] to its start.
    buf.clear();
    buf.resize(nc + 2, 0);
    for &c in &cells {
        if c != GONE {
            buf[c as usize - base + 1] += 1;
        }
    }
    for k in 1..nc + 1 {
        buf[k] += buf[k - 1];
    }
    let kept = buf[nc] as usize;
    buf[nc + 1] = kept as u32;
    let mut order = vec![0u32; kept];
    let mut sorted_cells = vec![0u32; kept];
    for (i, &c) in cells.iter().enumerate().rev() {
        if c != GONE {
            let end = &mut buf[c as usize - base + 1];
            *end -= 1;
            order[*end as usize] = i as u32;
            sorted_cells[*end as usize] = c;
        }
    }
    (order, sorted_cells, CellStarts { base, starts: &buf[1..] })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cell_sort_is_stable_drops_the_marked_and_counts_only_the_occupied_span() {
        // A 1 m box of 2 mm cells (about 250 000) with 400 particles in a corner of it, many
        // sharing a cell; every seventh particle has left.
        let g = Geometry::closed_box(0.0, 1.0, 0.0, 1.0, 0.004);
        let grid = Grid::new(&g, 0.002, 0.001);
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let pos: Vec<V3> = (0..400).map(|_| [0.3 + 0.02 * next(), 0.004 * next(), 0.5 + 0.02 * next()]).collect();
        let drop: Vec<bool> = (0..pos.len()).map(|i| i % 7 == 3).collect();
        let mut buf = Vec::new();
        let (order, cells, starts) = sort_by_cell(&grid, &pos, Some(&drop), &mut buf);
        let mut want: Vec<(u32, u32)> = (0..pos.len()).filter(|&i| !drop[i]).map(|i| (grid.index(grid.coords(pos[i])) as u32, i as u32)).collect();
        want.sort();
        assert_eq!(order, want.iter().map(|w| w.1).collect::<Vec<_>>(), "sorted by cell, input order within a cell");
        assert_eq!(cells, want.iter().map(|w| w.0).collect::<Vec<_>>());
        for c in 0..grid.cells() {
            let (s, e) = starts.range(c);
            let n = want.iter().filter(|w| w.0 as usize == c).count();
            assert_eq!(e - s, n, "cell {c}");
            assert!(want[s..e].iter().all(|w| w.0 as usize == c), "cell {c}");
        }
        assert!(buf.len() < grid.cells() / 20, "counted {} of {} cells", buf.len(), grid.cells());
    }
}
