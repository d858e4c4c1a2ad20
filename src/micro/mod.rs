//! Microstructure micromechanics: the `kind = "microstructure"` study.
//!
//! The deliverable (§5, Figs. 10–12) explains the particles' strength by their two-phase
//! microstructures — α-alumina with fused silica in sintered bauxite, quartz with Fe₂O₃ in the
//! granulated particles — and §6.1 argues that BL 16/30 is weaker because its soft phase does not
//! form a continuous matrix. This module makes that argument testable:
//!
//! * [`structure`]: labelled pixel grids; synthetic two-phase microstructures at a controlled area
//!   fraction and grain size, with the soft phase as a continuous matrix or as isolated pockets;
//!   the connectivity of each phase (clusters, largest cluster, percolation);
//! * [`image`]: a segmented micrograph (PNG labels or colours) as a pixel grid;
//! * [`material`]: the phase table (α-Al₂O₃, fused silica, quartz, Fe₂O₃) with sources;
//! * [`homogenise`]: periodic homogenisation with pixel-conforming bilinear quads (plane strain or
//!   plane stress), faer's sparse Cholesky; the effective stiffness, the Voigt, Reuss and
//!   Hashin–Shtrikman bounds;
//! * [`fields`]: virtual uniaxial tension and compression, the local maximum principal and von
//!   Mises stresses and strains, and hot-spot statistics per phase;
//! * [`failure`]: progressive failure, pixel by pixel (sequentially linear analysis): the crack
//!   path, the saw-tooth stress–strain path and the cell's strength;
//! * [`study`], [`solve`], [`run`], [`summary`], [`output`]: the study file, each structure's
//!   realisations built and solved, the run and its tables, the generated summary with the §6.1
//!   comparison, the maps and `.vtu` files;
//! * [`synth`]: the generator of the shipped synthetic segmented image.
//!
//! Verification (`tests/verification/micro.rs` and the unit tests): a single phase gives its own
//! stiffness and a uniform field; a laminate gives the exact Backus moduli (with ν = 0 in both
//! phases, exactly the Voigt and Reuss moduli along and across the layers); a dilute circular
//! inclusion carries Eshelby's stress within a stated tolerance that shrinks under refinement;
//! every effective modulus lies within the Hashin–Shtrikman bounds; the effective modulus of an
//! inclusion lattice converges under refinement.

pub mod failure;
pub mod fields;
pub mod homogenise;
pub mod image;
pub mod material;
pub mod output;
pub mod run;
pub mod solve;
pub mod structure;
pub mod study;
pub mod summary;
pub mod synth;

pub use run::run_microstructure;
pub use study::MicroStudy;
