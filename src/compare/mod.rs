//! Comparing light samplers: error metrics, error pictures, the convergence plot and the
//! report. Pure computation on images and numbers; the rendering and the files are
//! `commands::compare`'s.

pub mod html;
pub mod images;
pub mod metrics;
pub mod plot;
pub mod report;
