//! Verification against analytic and published answers, one reference problem per file
//! (`docs/reference.md`). Each test
//! states its tolerance: half a unit in the last printed digit of the reference unless noted.

mod verification {
    mod crush_fe;
    mod discrepancy;
    mod dem;
    mod experiments;
    mod gp;
    mod hertz;
    mod jh2;
    mod koh;
    mod lsq;
    mod mcmc;
    mod micro;
    mod lifetime;
    mod sobol;
    mod strength;
    mod uq;
    mod weibull;
}
