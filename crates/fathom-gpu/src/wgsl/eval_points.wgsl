// Evaluates the tape at a list of points: the GPU side of the GPU-vs-CPU conformance tests
// and of `Gpu::eval_points`.

@group(1) @binding(0) var<storage, read> points: array<vec4f>;
@group(1) @binding(1) var<storage, read_write> results: array<Val>;

@compute @workgroup_size(64)
fn eval_points(@builtin(global_invocation_id) gid: vec3u) {
    let i = gid.x;
    if i >= arrayLength(&points) {
        return;
    }
    results[i] = eval_tape(points[i].xyz);
}
