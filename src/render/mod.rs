//! Pictures: plots of profiles against exact solutions (PNG, no system libraries; the font
//! is embedded). Particle images (column density, slices) will join here.

pub mod plot;
