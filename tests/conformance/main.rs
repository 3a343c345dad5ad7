//! The one integration-test binary (DESIGN 9): the command line, and (with the backends) cross-backend
//! conformance.

mod cli;
mod suite;
