//! Documented limits on user input, checked before anything is allocated for it.
//!
//! They keep a scene small enough for the GPU interpreter's fixed-size stacks and keep one
//! evaluation bounded in time. Every limit is enforced where the input enters (scene parser,
//! `Scene::validate`, tape compiler) with an error naming the limit.

/// Most nodes in one scene tree.
pub const MAX_NODES: usize = 1024;
/// Deepest tree (a lone root has depth 1). Also bounds the point stack of the tape.
pub const MAX_TREE_DEPTH: usize = 32;
/// Most operators in one node's list or in the IFS loop.
pub const MAX_OPS_PER_LIST: usize = 64;
/// Most IFS loop iterations.
pub const MAX_IFS_ITERATIONS: u32 = 256;
/// Most instructions in one tape.
pub const MAX_TAPE_LEN: usize = 16384;
/// Most slots in one parameter buffer.
pub const MAX_PARAMS: usize = 65536;
/// Deepest point stack the interpreter keeps (tree depth plus the IFS loop's level).
pub const MAX_POINT_STACK: usize = MAX_TREE_DEPTH + 2;
/// Deepest value stack the interpreter keeps.
pub const MAX_VALUE_STACK: usize = MAX_TREE_DEPTH + 2;
/// Most lights.
pub const MAX_LIGHTS: usize = 8;
/// Most sphere-tracing steps per ray.
pub const MAX_STEPS: u32 = 10_000;
/// Largest scene file read, in bytes.
pub const MAX_SCENE_FILE_BYTES: u64 = 4 << 20;
