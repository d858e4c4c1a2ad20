//! Particle snapshots as VTK XML PolyData (`.vtp`, ASCII), one vertex per particle with its
//! id, diameter, velocity, speed and angular velocity as point data. ParaView opens them
//! directly; render the points as spheres with "Point Gaussian" scaled by `diameter`.

use std::fmt::Write as _;

use super::particles::Particles;
use crate::io::vtk_data_array;

/// The `.vtp` text of the particles at time `time`.
pub fn polydata(p: &Particles, time: f64) -> String {
    let n = p.len();
    let mut s = String::with_capacity(200 + n * 160);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n");
    s.push_str("<FieldData>\n<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">");
    let _ = write!(s, "{time:e}");
    s.push_str("</DataArray>\n</FieldData>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">");
    s.push_str("<PointData Scalars=\"diameter\" Vectors=\"velocity\">\n");
    vtk_data_array(&mut s, "Int64", "id", 1, p.id.iter().map(|&v| v as f64), true);
    vtk_data_array(&mut s, "Float64", "diameter", 1, p.radius.iter().map(|&r| 2.0 * r), false);
    vtk_data_array(&mut s, "Float64", "velocity", 3, p.vel.iter().flat_map(|v| v.iter().copied()), false);
    vtk_data_array(&mut s, "Float64", "speed", 1, p.vel.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()), false);
    vtk_data_array(&mut s, "Float64", "angular_velocity", 3, p.omega.iter().flat_map(|v| v.iter().copied()), false);
    s.push_str("</PointData>\n<Points>\n");
    vtk_data_array(&mut s, "Float64", "Points", 3, p.pos.iter().flat_map(|v| v.iter().copied()), false);
    s.push_str("</Points>\n<Verts>\n");
    vtk_data_array(&mut s, "Int64", "connectivity", 1, (0..n).map(|k| k as f64), true);
    vtk_data_array(&mut s, "Int64", "offsets", 1, (1..=n).map(|k| k as f64), true);
    s.push_str("</Verts>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    s
}

/// Reads the points and a named scalar back from a `.vtp` written by [`polydata`] (a check
/// that the file is complete and consistent; not a general VTK reader).
pub fn read_points(text: &str) -> Option<(Vec<[f64; 3]>, usize)> {
    let piece = text.find("<Piece NumberOfPoints=\"")?;
    let rest = &text[piece + 23..];
    let n: usize = rest[..rest.find('"')?].parse().ok()?;
    let pts = text.find("Name=\"Points\"")?;
    let body = &text[pts..];
    let open = body.find('>')? + 1;
    let close = body.find("</DataArray>")?;
    let nums: Vec<f64> = body[open..close].split_whitespace().map(|t| t.parse().ok()).collect::<Option<_>>()?;
    if nums.len() != 3 * n {
        return None;
    }
    Some((nums.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(), n))
}
