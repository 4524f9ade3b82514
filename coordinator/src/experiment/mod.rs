//! Reproductions of the experiments in the seed notes.
//!
//! | module | experiment |
//! |---|---|
//! | [`seed002`] | §4 of seed 002: A*, Basic Theta* and Lazy Theta* on 50 x 50 m fields with 10/20/30 % random circular obstacles, beside the thesis's Table 3.1 |

pub mod seed002;
