#!/usr/bin/python3
"""The scatter grid's photon noise on the Disney cloud per CPU second (issue 12, helper photvar).

Renders scenes/disney_cloud.json with `mfs` at 128 x 128, 1 spp, --threads 2, for seeds 1..S, and
reports per option set:
  noise   the photon noise of one image: the seeds' per-bin (4 x 4) sample variance of luminance,
          its root mean over the bins where the reference is >= 0.05 x its mean, divided by the
          reference's mean there (for two seeds: nimbus compare --bin 4 --min-ref 0.05's rel RMSE / sqrt 2,
          but normalised by the reference, so light-by-light runs add up); in parentheses the pairs'
          (1,2), (3,4), ... compare rel RMSE / sqrt(2);
  ref     binned rel RMSE and mean error of each image against the 512-spp reference (mean over seeds);
  cpu     user + sys of the 1-spp render, and of the set-up alone (--res 4x3), mean over seeds;
  fom     noise^2 x set-up CPU (lower is better).
Usage: photon_noise.py --nimbus build/bin/nimbus --label NAME [--seeds 2] [--set integrator.X=V ...]
Several option sets: --variant 'name:integrator.a=1;integrator.b=2' (repeatable; 'base:' = none).
--scene NAME: a scene of validation/mfs_validation.py's suite instead of the cloud, at its reference's
size, against --refs/NAME_pt2048.exr (validation/setup_error.py's references); --res applies to the cloud.
"""
import argparse, json, math, os, resource, subprocess, sys

import numpy as np

from exr_reader import read_exr

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, '..', 'scenes', 'disney_cloud.json')
REF = ['/work/main/validation/refs/disney_cloud_128x128_pt512.exr']  # --scene replaces it


def timed(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def compare(nimbus, a, b):
    out = subprocess.run([nimbus, 'compare', a, b, '--bin', '4', '--min-ref', '0.05', '--json'],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def binned_luminance(path):
    ch = read_exr(path)[0]
    lum = 0.2126 * ch['R'].astype(float) + 0.7152 * ch['G'].astype(float) + 0.0722 * ch['B'].astype(float)
    h, w = lum.shape
    return lum.reshape(h // 4, 4, w // 4, 4).mean(axis=(1, 3))


def seed_noise(paths):
    """sqrt(mean over the reference's bins >= 0.05 x its mean of the seeds' sample variance) / the
    reference's mean over those bins: the rel RMSE of one image against its own mean (for two seeds,
    the pair's compare rel RMSE / sqrt(2) up to the normalisation by the reference)."""
    ref = binned_luminance(REF[0])
    mask = ref >= 0.05 * ref.mean()
    imgs = np.stack([binned_luminance(p) for p in paths])
    var = imgs.var(axis=0, ddof=1)
    return math.sqrt(var[mask].mean()) / ref[mask].mean()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--nimbus', required=True)
    ap.add_argument('--label', required=True)
    ap.add_argument('--seeds', type=int, default=2)
    ap.add_argument('--variant', action='append', default=[])
    ap.add_argument('--res', default='128x128')
    ap.add_argument('--no-setup', action='store_true', help='skip the 4x3 set-up timing')
    ap.add_argument('--scene', help="a scene of mfs_validation.py's suite instead of the cloud")
    ap.add_argument('--refs', default='/work/refs', help='references for --scene')
    args = ap.parse_args()
    scene = SCENE
    if args.scene:
        sys.path.insert(0, HERE)
        import mfs_validation as mv
        s, base, _ = mv.suite()[args.scene]
        scene = os.path.join(base, f'.photon_noise_{os.getpid()}.json')
        json.dump(s, open(scene, 'w'))
        REF[0] = os.path.join(args.refs, f'{args.scene}_pt2048.exr')
        h, w = binned_luminance(REF[0]).shape
        args.res = f'{4 * w}x{4 * h}'
    variants = args.variant or ['base:']
    out_dir = f'/tmp/photon_noise/{args.label}'
    os.makedirs(out_dir, exist_ok=True)
    rows = []
    for v in variants:
        name, _, sets = v.partition(':')
        extra = []
        for s in filter(None, sets.split(';')):
            extra += ['--set', s]
        imgs, cpu, setup = [], [], []
        for seed in range(1, args.seeds + 1):
            img = f'{out_dir}/{name}_s{seed}.exr'
            base = [args.nimbus, 'render', scene, '--integrator', 'mfs', '--spp', '1', '--threads', '2',
                    '--seed', str(seed), '-q'] + extra
            cpu.append(timed(base + ['--res', args.res, '-o', img]))
            if not args.no_setup:
                setup.append(timed(base + ['--res', '4x3', '-o', f'{out_dir}/{name}_s{seed}_4x3.exr']))
            imgs.append(img)
        pairs = [(imgs[i], imgs[i + 1]) for i in range(0, len(imgs) - 1, 2)]
        noise = [compare(args.nimbus, a, b)['rel_rmse'] / math.sqrt(2) for a, b in pairs]
        refs = [compare(args.nimbus, a, REF[0]) for a in imgs]
        r = dict(name=name, sets=sets, noise=seed_noise(imgs), noises=noise,
                 ref_rmse=sum(x['rel_rmse'] for x in refs) / len(refs),
                 ref_mean=sum(x['mean_rel_error'] for x in refs) / len(refs),
                 cpu=sum(cpu) / len(cpu), setup=(sum(setup) / len(setup)) if setup else float('nan'))
        r['fom'] = r['noise'] ** 2 * r['setup'] * 1e4
        rows.append(r)
        print(f"{name:14s} noise {100*r['noise']:5.2f} %  ({', '.join(f'{100*n:.2f}' for n in noise)})  "
              f"ref rmse {100*r['ref_rmse']:5.2f} %  mean {100*r['ref_mean']:+5.2f} %  "
              f"cpu {r['cpu']:5.2f} s  setup {r['setup']:5.2f} s  fom {r['fom']:6.2f}", flush=True)
    with open(f'{out_dir}/result.json', 'w') as f:
        json.dump(rows, f, indent=1)
    if scene != SCENE:
        os.remove(scene)


if __name__ == '__main__':
    main()
