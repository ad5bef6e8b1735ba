//! Whole techniques compared with the reference (DESIGN 4, second level): one file per
//! technique, each rendering a frame on both backends and comparing photon statistics and
//! images after the technique's own filter.

pub mod sspm;
