//! Procedurally generated test objects, embedded so demos, tests and
//! benches need no input files. (The tissue model's head phantom lives in
//! `tissue::phantom`.)
