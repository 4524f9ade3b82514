//! Terrain relief and hazard, after seed 002 (Hrytsenko 2024, "Lazy Theta* for s-bot motion
//! taking terrain relief into account").
//!
//! | module | concept |
//! |---|---|
//! | [`TerrainParams`], [`HazardWeights`] (here) | the limits and weights, with the thesis's defaults |
//! | [`relief`] | [`TerrainFactors`]: slope, roughness and relief amplitude per cell from a height map |
//! | [`hazard`] | [`HazardMap`]: the hazard index `R` per cell, the chord weight [`alpha`], route hazard `c` |
//!
//! # What is the thesis's and what is filled in
//!
//! Labels as in the seed notes: **\[thesis\]** is stated in the thesis, **\[inferred\]** is our
//! choice where the thesis is silent.
//!
//! * **\[thesis\]** A square grid of step `e` whose cells carry slope and height; vertices at
//!   cell centres, 8-connected. Default `e = 1 m` ([`TerrainParams::cell_size`]).
//! * **\[thesis\]** Three factors: slope angle, roughness = 3-D surface area / projected area,
//!   relief amplitude = max - min height along the motion. Limits: **30°** slope and
//!   **0.20 m** amplitude; a cell over either cannot be crossed. Both are configurable.
//! * **\[inferred\]** How the factors are computed from one height per cell: Horn's 3x3
//!   gradient for the slope, Jenness's eight-triangle surface-area ratio for the roughness,
//!   and for the amplitude the largest *step* along the four lines through the cell (the
//!   change of rise between the two halves of the line, so a steady slope adds nothing: it
//!   has its own limit). See [`relief`].
//! * **\[thesis\]** A hazard index `R(i, j)` per cell. **\[inferred\]** Its formula (the thesis has
//!   none): `R = inf` over a limit, else
//!   `(w_s * slope/max_slope + w_r * (rho - 1)/(rho_max - 1) + w_h * amplitude/max_amplitude)
//!   / (w_s + w_r + w_h)`, so `R` is in `[0, 1]` (default weights 0.4 / 0.2 / 0.4; roughness
//!   weighs less because on a height map it mostly repeats the slope). An optional roughness
//!   limit is off by default (the thesis gives none).
//! * **\[thesis\]** Route hazard `c = sum alpha * R` over the cells the route crosses, with
//!   `alpha = 1/2` if the route's chord in the cell is shorter than half a cell diagonal and
//!   `1` if longer (threshold printed as `sqrt2/(2e)`, read as `(sqrt2/2) e`). **\[inferred\]**:
//!   a chord equal to the threshold counts 1; the cells a route starts, ends or turns in
//!   count 1 (the robot stands in them; the thesis's worked example gives its start and goal
//!   cells weight 1); a cell touched only at a corner is not crossed; a cell crossed by two
//!   segments counts twice. See [`hazard`].
//! * **\[thesis\]** Evaluation `f = g + h + c` (eq. 3.1), `h` Euclidean. **\[inferred\]** To keep the
//!   search consistent, `c` is folded into the edge cost: a segment costs its length plus
//!   `lambda * (its share of c)`, with `lambda` ([`TerrainParams::hazard_weight`]) in metres
//!   per hazard unit, 1 by default, which is the thesis's sum taken literally.
//! * **\[inferred\]** A grid whose terrain layer is a *cost* layer (multipliers, see
//!   [`hnav_runtime::grid::TerrainKind::Cost`]) maps to `R = max(0, value - 1)`: crossing a
//!   whole cell then costs about `value` times its length, like the runtime defines it.

pub mod hazard;
mod params;
pub mod relief;

pub use hazard::{alpha, HazardMap, ALPHA_THRESHOLD};
pub use params::{HazardWeights, TerrainParams};
pub use relief::TerrainFactors;
