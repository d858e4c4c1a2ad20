//! The per-pixel outputs of a microstructure report: the map table the figures are drawn from,
//! and the `.vtu` for ParaView.

use std::fmt::Write as _;

use super::material::Phase;
use super::solve::Solved;
use crate::error::Result;
use crate::io::{ReportDir, fcol, scol, table, ucol, vtk_data_array};

/// Largest side of a map table.
pub const MAP_SIDE: usize = 256;

/// `map_<name>.csv`: the realisation's pixels in b × b blocks, b = ⌈max(nx, ny)/MAP_SIDE⌉ (1 up
/// to 256 pixels a side): the most frequent phase of a block (ties to the lower label), its
/// largest σ₁ in each test and its largest γ_max in tension — the largest, so that hot spots stay
/// visible when a map is coarsened.
pub fn write_map(dir: &mut ReportDir, name: &str, r: &Solved, phase_of_label: &[usize], phases: &[Phase]) -> Result<()> {
    let m = &r.micro;
    let b = m.nx.max(m.ny).div_ceil(MAP_SIDE);
    let (mx, my) = (m.nx.div_ceil(b), m.ny.div_ceil(b));
    let n = mx * my;
    let (mut bi, mut bj, mut x, mut y, mut phase) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut s1t, mut s1c, mut gt) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    let labels = phase_of_label.len();
    for j in 0..my {
        for i in 0..mx {
            let mut count = vec![0usize; labels];
            let (mut a, mut c, mut g) = (f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
            let (i1, j1) = ((i * b + b).min(m.nx), (j * b + b).min(m.ny));
            for pj in j * b..j1 {
                for pi in i * b..i1 {
                    let e = pj * m.nx + pi;
                    count[m.labels[e] as usize] += 1;
                    a = a.max(r.locals[0].sigma1[e]);
                    c = c.max(r.locals[1].sigma1[e]);
                    g = g.max(r.locals[0].shear_strain[e]);
                }
            }
            let top = (0..labels).fold(0, |best, l| if count[l] > count[best] { l } else { best });
            bi.push(i as u64);
            bj.push(j as u64);
            x.push(0.5 * (i * b + i1) as f64 * m.pixel_m);
            y.push(0.5 * (j * b + j1) as f64 * m.pixel_m);
            phase.push(phases[phase_of_label[top]].name.clone());
            s1t.push(a);
            s1c.push(c);
            gt.push(g);
        }
    }
    let mut t = table(vec![
        ucol("i", bi),
        ucol("j", bj),
        fcol("x_m", x),
        fcol("y_m", y),
        fcol("block_m", vec![b as f64 * m.pixel_m; n]),
        fcol("width_m", vec![m.nx as f64 * m.pixel_m; n]),
        fcol("height_m", vec![m.ny as f64 * m.pixel_m; n]),
        scol("phase", phase),
        fcol("sigma1_tension_pa", s1t),
        fcol("sigma1_compression_pa", s1c),
        fcol("shear_strain_tension", gt),
    ])?;
    dir.write_table(&format!("map_{name}"), &mut t)
}

/// `<name>.vtu`: the pixels as quads (m, z = 0), with the phase (index in the phase table) and
/// every measure of both tests as cell data.
pub fn write_vtu(dir: &mut ReportDir, name: &str, r: &Solved, phase_of_label: &[usize]) -> Result<()> {
    let m = &r.micro;
    let (nx, ny, h) = (m.nx, m.ny, m.pixel_m);
    let (np, ne) = ((nx + 1) * (ny + 1), nx * ny);
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{ne}\">");
    s.push_str("<Points>\n");
    vtk_data_array(&mut s, "Float64", "Points", 3, (0..np).flat_map(|p| [(p % (nx + 1)) as f64 * h, (p / (nx + 1)) as f64 * h, 0.0]), false);
    s.push_str("</Points>\n<Cells>\n");
    let node = |i: usize, j: usize| (j * (nx + 1) + i) as f64;
    vtk_data_array(&mut s, "Int64", "connectivity", 1, (0..ne).flat_map(|e| {
        let (i, j) = (e % nx, e / nx);
        [node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)]
    }), true);
    vtk_data_array(&mut s, "Int64", "offsets", 1, (1..=ne).map(|e| (4 * e) as f64), true);
    vtk_data_array(&mut s, "UInt8", "types", 1, (0..ne).map(|_| 9.0), true);
    s.push_str("</Cells>\n<CellData>\n");
    vtk_data_array(&mut s, "Int32", "phase", 1, m.labels.iter().map(|&l| phase_of_label[l as usize] as f64), true);
    for (t, test) in ["tension", "compression"].iter().enumerate() {
        let l = &r.locals[t];
        for (field, v) in [("sigma1_pa", &l.sigma1), ("von_mises_pa", &l.von_mises), ("strain1", &l.strain1), ("shear_strain", &l.shear_strain)] {
            vtk_data_array(&mut s, "Float64", &format!("{field}_{test}"), 1, v.iter().copied(), false);
        }
    }
    s.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    dir.write_bytes(&format!("{name}.vtu"), s.as_bytes())
}
