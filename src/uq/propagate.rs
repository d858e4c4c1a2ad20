//! Monte Carlo propagation of one strength model's comparison ([`super::setup::Setup`]).
//!
//! The samples come in `replicates` independent blocks (plain: own streams; LHS: own
//! hypercubes; Sobol': own random shifts). Every headline is the mean of the block estimates,
//! its standard error the sd of the block estimates over √blocks — valid for all three methods.
//! Within a block the samples are evaluated in parallel and collected in order, so the result
//! does not depend on the thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::setup::{Mode, Setup};
use super::study::{Method, Propagation};
use crate::error::Result;

/// The unit points of block r (n points in d dimensions).
pub fn block_points(method: Method, d: usize, n: usize, seed: u64, r: usize) -> Result<Vec<Vec<f64>>> {
    Ok(match method {
        Method::Plain => {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(r as u64 + 1);
            (0..n).map(|_| (0..d).map(|_| rng.random::<f64>()).collect()).collect()
        }
        Method::Lhs => crate::design::latin_hypercube(n, d, seed.wrapping_add(1 + r as u64)),
        Method::Sobol => crate::design::shifted_sobol(d, n, seed, r as u64 + 1)?,
    })
}

/// Mean and standard error over blocks.
pub fn mean_se(v: &[f64]) -> (f64, f64) {
    let (m, sd) = crate::stats::mean_and_sd(v);
    (m, sd / (v.len() as f64).sqrt())
}

/// One block of evaluated samples, flat: sample i has inputs `x[i·ni..]` and P `p[i·np..]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Samples.
    pub n: usize,
    /// Inputs (n × ni).
    pub x: Vec<f64>,
    /// P per material, horizon and damage model (n × np, [`Setup::slot`]).
    pub p: Vec<f64>,
}

/// The propagation result.
#[derive(Debug, Clone, PartialEq)]
pub struct Propagated {
    /// Blocks of evaluated samples.
    pub blocks: Vec<Block>,
    /// Inputs per sample.
    pub ni: usize,
    /// P values per sample.
    pub np: usize,
}

impl Propagated {
    /// Number of samples.
    pub fn count(&self) -> usize {
        self.blocks.iter().map(|b| b.n).sum()
    }

    /// P at `slot` over every sample.
    pub fn values(&self, slot: usize) -> Vec<f64> {
        self.blocks.iter().flat_map(|b| b.p.chunks(self.np).map(move |p| p[slot])).collect()
    }

    /// P at `slot` over the samples of block `b`.
    pub fn block_values(&self, b: usize, slot: usize) -> Vec<f64> {
        self.blocks[b].p.chunks(self.np).map(|p| p[slot]).collect()
    }

    /// Inputs of sample i of block b.
    pub fn x(&self, b: usize, i: usize) -> &[f64] {
        &self.blocks[b].x[i * self.ni..(i + 1) * self.ni]
    }

    /// Per block, the fraction of its first `first` samples in which slot `a` exceeds slot `b`.
    pub fn fraction_worse(&self, a: usize, b: usize, first: usize) -> Vec<f64> {
        self.blocks
            .iter()
            .map(|bl| {
                let k = first.min(bl.n);
                bl.p.chunks(self.np).take(k).filter(|p| p[a] > p[b]).count() as f64 / k as f64
            })
            .collect()
    }

    /// Fraction of all samples in which slots a and b are equal.
    pub fn ties(&self, a: usize, b: usize) -> f64 {
        self.blocks.iter().map(|bl| bl.p.chunks(self.np).filter(|p| p[a] == p[b]).count()).sum::<usize>() as f64 / self.count() as f64
    }
}

/// Runs the propagation of `setup` (joint sampling; rayon-parallel, independent of the thread
/// count); `tick` after each block.
pub fn propagate(setup: &Setup, p: &Propagation, seed: u64, tick: &(dyn Fn() + Sync)) -> Result<Propagated> {
    let d = setup.varying(Mode::Joint).len().max(1);
    let n = p.samples / p.replicates;
    let (ni, np) = (setup.inputs.len(), setup.outputs());
    // The replicate blocks side by side as well as each block's samples (a block's points are
    // drawn serially); errors in the blocks' order.
    let blocks: Vec<Result<Block>> = (0..p.replicates)
        .into_par_iter()
        .map(|r| {
            let pts = block_points(p.method, d, n, seed, r)?;
            let mut block = Block { n, x: vec![0.0; n * ni], p: vec![0.0; n * np] };
            block.x.par_chunks_mut(ni).zip(block.p.par_chunks_mut(np)).zip(&pts).try_for_each(|((x, pv), u)| {
                setup.values_into(u, Mode::Joint, x);
                setup.evaluate_into(x, Mode::Joint, pv)
            })?;
            tick();
            Ok(block)
        })
        .collect();
    Ok(Propagated { blocks: blocks.into_iter().collect::<Result<_>>()?, ni, np })
}
