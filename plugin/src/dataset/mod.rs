//! The voxel dataset component: the readers, the sparse store and the grids are the `firemedium-dataset`
//! crate's (re-exported here under their names); what the plugin adds is the dataset's parameter table — the
//! scene's `filename`, `format`, `source`, grid names and mappings read into load options ([`params`]), and what
//! they ask for loaded (`load`).

pub use firemedium_dataset::*;

mod load;
pub(crate) mod params;
