//! The published numbers the studies, the harness and the docs compare
//! against, each written in one place: the fits of the paper this model
//! comes from ([`paper`]) and the multi-contact study's closure values and
//! tables ([`multicontact`]). The numbers themselves are files in
//! `reference_data/`, compiled in; docs/reference-numbers.md explains them.

pub mod multicontact;
pub mod paper;
