#!/usr/bin/env python3
"""Mitsuba 3's side of `fathom bench volume` (not run in CI).

Exports the benchmark's Menger density as a .vol with `fathom volume --export`, renders it with
fathom (from the .vol, placed by its header's box) and with Mitsuba 3's `volpath` integrator
(heterogeneous medium, one global majorant, NEE, MIS) at the same camera, film and spp, and
prints JSON: paths per second of each, and the mean absolute difference between the images,
next to the difference between two Mitsuba seeds (the noise floor at that spp).

    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    apt-get install libllvm19     # Dr.Jit's LLVM backend needs LLVM >= 16 (Debian 12 has 15)
    /tmp/mi/bin/python crates/fathom-volume/bench/mitsuba_compare.py \
        --fathom target/release/fathom --grid 128 --spp 64 --out /tmp/mitsuba-compare

Scene (as in bench_volume.rs): the `menger` preset sampled over [-1,1]^3, sigma_t 20 inside,
albedo 0.8, isotropic, constant environment 1, Russian roulette after 5 bounces, 256x256, box
pixel filter, the preset's camera (vertical fov 40).
"""
import argparse, json, os, struct, subprocess, time

import numpy as np

EYE, TARGET, UP, FOV = (2.4, 1.9, 3.1), (0.0, -0.05, 0.0), (0.0, 1.0, 0.0), 40.0


def load_average():
    with open('/proc/loadavg') as f:
        return ' '.join(f.read().split()[:3])


def vol_box(path):
    with open(path, 'rb') as f:
        head = f.read(48)
    assert head[:4] == b'VOL\x03', 'not a .vol file'
    return struct.unpack('<6f', head[24:48])


def fathom(args, extra, out, stats):
    cmd = [args.fathom, 'volume', '--grid', args.vol, '--box', 'file', '--density-scale', '20',
           '--albedo', '0.8', '--g', '0', '--env', '1', '--eye', ','.join(map(str, EYE)),
           '--target', ','.join(map(str, TARGET)), '--up', ','.join(map(str, UP)),
           '--fov', str(FOV), '--size', f'{args.size}x{args.size}', '--spp', str(args.spp),
           '--max-depth', '1000', '--rr-depth', '5', '--threads', str(args.threads),
           '-o', out, '--stats', stats, '--quiet'] + extra
    subprocess.run(cmd, check=True)
    with open(stats) as f:
        return json.load(f)['render']


def read_exr(path, mi):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32))


def mitsuba_scene(mi, args, seed, majorant_factor):
    T = mi.ScalarTransform4f
    b = vol_box(args.vol)
    lo, hi = np.array(b[:3]), np.array(b[3:])
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    medium = {
        'type': 'heterogeneous',
        'sigma_t': {'type': 'gridvolume', 'filename': args.vol,
                    'to_world': T().translate(lo.tolist()).scale((hi - lo).tolist())},
        'scale': 20.0,
        'albedo': 0.8,
        'phase': {'type': 'isotropic'},
    }
    if majorant_factor:
        medium['majorant_resolution_factor'] = majorant_factor
    return mi.load_dict({
        'type': 'scene',
        'integrator': {'type': 'volpath', 'max_depth': -1, 'rr_depth': 5},
        'sensor': {
            'type': 'perspective', 'fov': FOV, 'fov_axis': 'y',
            'to_world': T().look_at(origin=EYE, target=TARGET, up=UP),
            'film': {'type': 'hdrfilm', 'width': args.size, 'height': args.size,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'},
            'sampler': {'type': 'independent', 'sample_count': args.spp, 'seed': seed},
        },
        'emitter': {'type': 'constant', 'radiance': {'type': 'rgb', 'value': 1.0}},
        'cube': {'type': 'cube', 'to_world': T().translate(centre.tolist()).scale(half.tolist()),
                 'bsdf': {'type': 'null'}, 'interior': medium},
    })


def mitsuba_render(mi, args, seed, majorant_factor=0):
    scene = mitsuba_scene(mi, args, seed, majorant_factor)
    if args.variant.startswith('llvm'):
        # Compile the kernel once at this spp (seed 0), then time a second render.
        mi.render(scene, seed=seed + 1000, spp=args.spp).numpy()
    t = time.perf_counter()
    img = np.array(mi.render(scene, seed=seed, spp=args.spp))
    secs = time.perf_counter() - t
    return img, args.size * args.size * args.spp / secs, secs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--fathom', default='target/release/fathom')
    ap.add_argument('--grid', type=int, default=128)
    ap.add_argument('--spp', type=int, default=64)
    ap.add_argument('--size', type=int, default=256)
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--variant', default='llvm_ad_rgb')
    ap.add_argument('--out', default='/tmp/mitsuba-compare')
    ap.add_argument('--majorant-factor', type=int, default=0,
                    help="also time Mitsuba's majorant supergrid with this resolution factor (0: skip)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    args.vol = os.path.join(args.out, f'menger{args.grid}.vol')
    subprocess.run([args.fathom, 'volume', '--preset', 'menger', '--grid', str(args.grid),
                    '--box', '-1,-1,-1,1,1,1', '--export', args.vol, '--quiet'], check=True)

    if args.variant.startswith('llvm') and 'DRJIT_LIBLLVM_PATH' not in os.environ:
        for p in ('/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1', '/usr/lib/x86_64-linux-gnu/libLLVM-19.so'):
            if os.path.exists(p):
                os.environ['DRJIT_LIBLLVM_PATH'] = p
                break
    import mitsuba as mi
    mi.set_variant(args.variant)
    result = {'grid': f'{args.grid}^3', 'size': f'{args.size}x{args.size}', 'spp': args.spp,
              'mitsuba': mi.__version__, 'variant': args.variant, 'load_average_start': load_average()}

    ours = {}
    for name, extra in [('grid_homogeneous', []), ('grid', ['--no-homogeneous']),
                        ('global', ['--majorant', 'global', '--no-homogeneous'])]:
        exr = os.path.join(args.out, f'fathom-{name}.exr')
        st = fathom(args, extra, exr, os.path.join(args.out, f'fathom-{name}.json'))
        ours[name] = {'paths_per_second': st['paths_per_second'], 'image': read_exr(exr, mi),
                      'mean_path_length': st['mean_path_length'], 'load_average': load_average()}

    mits = []
    for seed in (1, 2):
        img, pps, secs = mitsuba_render(mi, args, seed)
        mits.append({'paths_per_second': pps, 'seconds': secs, 'image': img, 'load_average': load_average()})
    mi_img = mits[0]['image']
    np.save(os.path.join(args.out, 'mitsuba.npy'), mi_img)
    mi.Bitmap(mi_img).write(os.path.join(args.out, 'mitsuba.exr'))

    def mad(a, b):
        return float(np.mean(np.abs(a - b)))

    result['mitsuba_volpath'] = {
        'paths_per_second': [m['paths_per_second'] for m in mits],
        'seconds': [m['seconds'] for m in mits],
        'load_average': [m['load_average'] for m in mits],
        'image_mean': float(mi_img.mean()),
    }
    if args.majorant_factor:
        # Newer Mitsuba versions may have a majorant supergrid; 3.9's heterogeneous medium
        # refuses the property as unreferenced.
        try:
            _, pps, secs = mitsuba_render(mi, args, 3, args.majorant_factor)
            grid = {'factor': args.majorant_factor, 'paths_per_second': pps, 'seconds': secs}
        except RuntimeError as e:
            grid = {'factor': args.majorant_factor, 'unsupported': str(e).splitlines()[0]}
        result['mitsuba_volpath']['majorant_supergrid'] = grid
    result['noise_floor_mad_mitsuba_seed1_vs_seed2'] = mad(mits[0]['image'], mits[1]['image'])
    mi_pps = max(m['paths_per_second'] for m in mits)
    for name, o in ours.items():
        result[f'fathom_{name}'] = {
            'paths_per_second': o['paths_per_second'],
            'speedup_vs_mitsuba': o['paths_per_second'] / mi_pps,
            'mean_path_length': o['mean_path_length'],
            'image_mean': float(o['image'].mean()),
            'mad_vs_mitsuba_seed1': mad(o['image'], mits[0]['image']),
            'mad_vs_mitsuba_seed2': mad(o['image'], mits[1]['image']),
            'load_average': o['load_average'],
        }
    result['load_average_end'] = load_average()
    print(json.dumps(result, indent=2))


if __name__ == '__main__':
    main()
