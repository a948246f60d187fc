// The tape interpreter (mirrors fathom-core eval.rs; the encoding is docs/tape.md). The
// `op_*` dispatch functions it calls are generated in Rust from the registry tables.

// MAX_STACK (stack depth) and MAX_EXECUTED (the bound on executed instructions, so a corrupt
// tape cannot hang the device) come from fathom_core::shared.

// The stacks live in private memory: zero-initialised once per invocation rather than on every
// call of `eval_tape` (a function-local array would be cleared each time). A valid tape always
// pushes before it reads, so stale entries from an earlier call are never seen.
var<private> pts: array<Pt, MAX_STACK>;
var<private> vals: array<Val, MAX_STACK>;
var<private> loop_rem: array<u32, 4>;
var<private> loop_body: array<u32, 4>;

fn eval_tape(pw: vec3f) -> Val {
    var p = pw;
    var k = 1.0;
    var trap = NO_TRAP;
    var np = 0u;
    // The top of the value stack stays in registers (`top`); `vals[0 .. nv - 1]` hold the
    // values below it, so a tape of one shape never touches the array.
    var top = val_solid(1e20, 0.0, NO_TRAP);
    var nv = 0u;
    var nl = 0u;
    var pc = 0u;
    var step = 0u;
    let len = arrayLength(&instrs);
    loop {
        // The cheap instructions (stack moves, loop bounds, distance modifiers, combines) run
        // in this tight inner loop; it leaves only for a shape or a domain operator, so the
        // big dispatch below (every primitive, fractal and transform, all inlined) is entered
        // once per expensive instruction instead of once per instruction. On lavapipe, which
        // runs 8 invocations per SIMD thread, that halves the time of tapes with a tree.
        var fam = 0u;
        var i = 0u;
        var a = 0u;
        var z = 0u;
        loop {
            step += 1u;
            if pc >= len || step > MAX_EXECUTED {
                fam = 0u;
                i = 0u;
                break;
            }
            let ins = instrs[pc];
            pc += 1u;
            fam = ins.x >> 8u;
            i = ins.x & 0xffu;
            a = ins.y;
            z = ins.z;
            if fam == 0u {
                if i == 0u {
                    break;
                } else if i == 1u {
                    pts[np] = Pt(p, k, trap);
                    np += 1u;
                } else if i == 2u {
                    np -= 1u;
                    let s = pts[np];
                    p = s.p;
                    k = s.k;
                    trap = s.trap;
                } else if i == 3u {
                    let n = u32(params[a]);
                    if n == 0u {
                        pc = z;
                    } else {
                        loop_rem[nl] = n;
                        loop_body[nl] = pc;
                        nl += 1u;
                    }
                } else if i == 4u {
                    trap = min(trap, length(p));
                    loop_rem[nl - 1u] -= 1u;
                    if loop_rem[nl - 1u] > 0u {
                        pc = z;
                    } else {
                        nl -= 1u;
                    }
                }
            } else if fam == 4u {
                top.d = op_mod(i, a, top.d, k);
            } else if fam == 5u {
                top = op_comb(i, a, vals[nv - 2u], top, k);
                nv -= 1u;
            } else if fam <= 3u {
                break;
            }
        }
        if fam == 0u {
            // The end of the tape (or of the step budget).
            break;
        }
        if fam == 3u {
            op_xf(i, a, &p, &k);
        } else {
            var d = 1e20;
            var t = trap;
            if fam == 1u {
                d = op_prim(i, a, p);
            } else {
                let e = op_frac(i, a, p);
                d = e.x;
                t = min(e.y, trap);
            }
            if nv > 0u {
                vals[nv - 1u] = top;
            }
            top = val_solid(d * k, f32(z), t);
            nv += 1u;
        }
    }
    return top;
}

fn eval_distance(p: vec3f) -> f32 {
    return eval_tape(p).d;
}
