use super::*;

#[test]
fn placeholder_mesh_tests_compile() {}
