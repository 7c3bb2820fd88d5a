//! Procedurally generated test objects, embedded so demos, tests and
//! benches need no input files: the voxel objects of seed 003 in
//! [`voxel`]. (The tissue model's head phantom lives in `tissue::phantom`.)

pub mod voxel;
