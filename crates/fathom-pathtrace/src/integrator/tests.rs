//! Tests of the integrator.
