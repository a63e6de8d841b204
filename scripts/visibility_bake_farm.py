"""Spread a visibility bake over a render farm (e.g. Flamenco jobs): each task
bakes a frame range of one object headless and writes a training-set piece
(.pvis); a last task merges the pieces, fits the pose model and stores it on
the object.

    blender -b scene.blend --python scripts/visibility_bake_farm.py -- \\
        bake --object Body --frames 1-48 --step 2 --rays 256 --out /farm/body_001.pvis
    blender -b scene.blend --python scripts/visibility_bake_farm.py -- \\
        fit --object Body --lobes 2 --model /farm/body.pzh --save /farm/body_*.pvis

The add-on is taken from an installed Penumbra, or from build/addon next to
this script. Exit status 1 with a message on any error."""

import argparse
import glob
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def load_addon():
    try:
        import penumbra  # installed add-on
    except ImportError:
        sys.path.insert(0, os.path.join(ROOT, "build", "addon"))
        import penumbra
    if not hasattr(bpy.types.Object, "penumbra_visibility"):
        penumbra.register()
    return penumbra


def parse(argv):
    parser = argparse.ArgumentParser(prog="visibility_bake_farm")
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("bake", help="bake one frame range into a .pvis piece")
    b.add_argument("--object", required=True)
    b.add_argument("--frames", required=True, help="first-last, e.g. 1-48")
    b.add_argument("--step", type=int, default=1)
    b.add_argument("--rays", type=int, default=256)
    b.add_argument("--order", type=int, default=4)
    b.add_argument("--below-horizon", default="occluded", choices=("occluded", "cast"))
    b.add_argument("--actions", default="", help="comma-separated actions baked in turn (default: what plays now)")
    b.add_argument("--out", required=True)
    f = sub.add_parser("fit", help="merge pieces, fit, write the model")
    f.add_argument("--object", required=True)
    f.add_argument("--lobes", type=int, default=2)
    f.add_argument("--model", required=True)
    f.add_argument("--save", action="store_true", help="save the .blend with the model recorded on the object")
    f.add_argument("pieces", nargs="+")
    return parser.parse_args(argv)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args = parse(argv)
    load_addon()
    from penumbra import native
    from penumbra.visibility import bake
    obj = bpy.data.objects.get(args.object)
    if obj is None:
        raise SystemExit(f"visibility_bake_farm: no object named '{args.object}'")
    if args.command == "bake":
        first, last = (int(x) for x in args.frames.split("-"))
        actions = []
        for name in filter(None, (n.strip() for n in args.actions.split(","))):
            if name not in bpy.data.actions:
                raise SystemExit(f"visibility_bake_farm: no action named '{name}'")
            actions.append(bpy.data.actions[name])
        started = time.perf_counter()
        job, training = bake.bake_training_set(
            bpy.context, obj, first, last, args.step, rays=args.rays, sh_order=args.order,
            occluders=obj.penumbra_visibility.occluders, below_horizon=args.below_horizon,
            log=lambda line: print(line, flush=True), actions=actions)
        training.save(args.out)
        print(f"visibility_bake_farm: {len(training)} frames in {time.perf_counter() - started:.1f} s → {args.out}")
    else:
        paths = sorted({p for pattern in args.pieces for p in glob.glob(pattern)})
        if not paths:
            raise SystemExit("visibility_bake_farm: no pieces found")
        pieces = [native.require().visibility.TrainingSet.load(p) for p in paths]
        model, summary = bake.fit_and_store(obj, pieces, args.lobes, os.path.abspath(args.model))
        print(f"visibility_bake_farm: {summary['frames']} frames from {len(paths)} pieces, "
              f"held-out AO error {summary['model_holdout']['ao_mean_abs']:.4f} → {args.model}")
        if args.save:
            bpy.ops.wm.save_mainfile()


if __name__ == "__main__":
    try:
        main()
    except (ValueError, OSError, RuntimeError) as error:
        print(f"visibility_bake_farm: {error}", file=sys.stderr)
        sys.exit(1)
