//! Reports of a fit: the report and its tables, and plots (seed Figure 3 and time
//! histories) with the `plots` feature.

#[cfg(feature = "plots")]
pub mod plots;
pub mod summary;
pub mod tables;
