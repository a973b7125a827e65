//! Reports of a fit: plots (seed Figure 3 and time histories).

pub mod plots;
pub mod summary;
pub mod tables;
