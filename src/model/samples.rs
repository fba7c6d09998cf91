//! The paper's example as builder calls.
