//! Tests of the runner on the paper's press and built-in problems (closed forms, physical
//! expectations, energy balance, event counts) and of runs until periodic.

mod edges;
mod simulate;
mod steady;
mod window;
