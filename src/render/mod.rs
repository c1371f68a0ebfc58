//! Pictures, as PNG without system libraries (the font is embedded): plots of profiles
//! against exact solutions (`plot`), and particle images — column density, projections and
//! slices of SPH fields — built from a snapshot by kernel interpolation (`interpolate`),
//! coloured (`colormap`) and drawn with axes and a colour bar (`image`), with the Roche lobes
//! of a binary run drawn over them (`overlay`); movie frames of a whole run (`movie`).

pub mod colormap;
pub mod image;
pub mod interpolate;
pub mod movie;
pub mod overlay;
pub mod plot;
