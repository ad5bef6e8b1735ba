//! Whole techniques compared with the reference (the second level of comparison, see
//! [`crate::harness`]): one file per
//! technique, each rendering a frame on both backends and comparing photon statistics and
//! images after the technique's own filter.

pub mod sspm;
