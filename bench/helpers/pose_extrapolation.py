"""Ways of keeping the linear pose model from extrapolating, measured on
held-out frames without changing the model (issue #27 item 7): each uses the
training frames alone. The model's features are R − I, linear in the
rotation's entries, and `PoseModel.synthesize` takes any finite 3×3, so a
pose moved in feature space is evaluated as I + φ': what a clamp in the
core's pose_features would give, before building one."""

import numpy as np

from bench.helpers.visibility_criteria import GOAL, frame_ao


def _principal_coordinates(phi):
    """Per joint, the mean and right singular vectors of the training
    features phi (frames, joints, 9): every direction, kept or not."""
    mean = phi.mean(axis=0)
    basis = np.stack([np.linalg.svd(phi[:, j] - mean[j], full_matrices=True)[2] for j in range(phi.shape[1])])
    return mean, basis


def _clamped_to_training_range(phi_train, phi):
    """Each joint's features clamped, along its principal directions over
    the training frames, to the range the training frames span."""
    mean, basis = _principal_coordinates(phi_train)
    coords = lambda x: np.einsum("jab,fjb->fja", basis, x - mean)  # noqa: E731
    z_train = coords(phi_train)
    z = np.clip(coords(phi), z_train.min(axis=0), z_train.max(axis=0))
    return np.einsum("jab,fja->fjb", basis, z) + mean


def _model_sh(core, model, phi, threads):
    """The model's SH visibility (frames, V, order²) at features phi (frames, joints, 9)."""
    out = []
    for p in phi:
        _, _, params = model.synthesize((np.eye(3) + p.reshape(-1, 3, 3)).astype(np.float32), threads=threads)
        out.append(core.visibility.zh_params_to_sh(params.astype(np.float64)))
    return np.stack(out)


def alternatives(core, model, rotations_train, rotations_held, baked_train, reference, bake_error, threads=0):
    """[{"name", "mean", "worst", "past"}] per way (the model as fitted
    first): mean and worst per-frame ratio of |ΔAO| against `reference`
    (V, held frames: Cycles) over `bake_error` (per held frame: the
    per-frame bake's), and the frames past GOAL. rotations_*: (frames,
    model joints, 3, 3); baked_train: the training frames' SH (frames, V,
    order²)."""
    phi_train = (rotations_train - np.eye(3)).reshape(len(rotations_train), -1, 9)
    phi_held = (rotations_held - np.eye(3)).reshape(len(rotations_held), -1, 9)
    distance = ((phi_held.reshape(len(phi_held), 1, -1) - phi_train.reshape(1, len(phi_train), -1)) ** 2).sum(-1)
    nearest = distance.argmin(axis=1)
    plain = _model_sh(core, model, phi_held, threads)
    ways = {"the model as fitted": lambda: plain,
            "each joint's features clamped to their training range": lambda: _model_sh(
                core, model, _clamped_to_training_range(phi_train, phi_held), threads)}
    for t in (0.25, 0.5):
        ways[f"the pose moved {t:g} of the way to the nearest training pose"] = lambda t=t: _model_sh(
            core, model, (1 - t) * phi_held + t * phi_train[nearest], threads)
    for a in (0.25, 0.5):
        ways[f"SH blended {a:g} toward the nearest training frame's bake"] = lambda a=a: (
            (1 - a) * plain + a * baked_train[nearest])
    ways["SH blended 0.1 toward the training frames' mean"] = lambda: 0.9 * plain + 0.1 * baked_train.mean(axis=0)
    out = []
    for name, sh in ways.items():
        error = np.abs(frame_ao(core, sh()) - reference).mean(axis=0)
        ratios = error / bake_error
        out.append({"name": name, "mean": float(error.mean() / bake_error.mean()), "worst": float(ratios.max()),
                    "past": int((ratios > GOAL).sum())})
    return out
