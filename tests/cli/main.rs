//! End-to-end tests of the `chisel` binary: every command on real data,
//! JSON reports, exit codes, and clear errors (never a panic) on bad files.
//!
//! One binary, one module per command (`scan` included), and
//! `cross_command` for what all commands share; `support` runs the binary.

#[path = "../common/mod.rs"]
mod common;
mod support;

mod bench;
mod blobby;
mod convert;
mod cross_command;
mod cut;
mod demo;
mod fuse;
mod hull;
mod implicit;
mod info;
mod mc;
mod morph;
mod polyhedrize;
mod relax;
mod render;
mod scan;
mod spline;
mod stats;
