"""The World's lighting as SH coefficients, for the frame shading and the GPU
preview, and the cache of its images' projections."""

import numpy as np

from .. import color, native, world
from .input_error import VisibilityInputError

# The World is read by penumbra.world (its wiring, lookups, pixels and colour
# space), as the light rig reads it: the sum of every Background that lights
# the scene. Here each Background becomes SH coefficients; SH projection is
# linear, so the World's SH is the weighted sum of its Backgrounds'.

# Projections of the World's images, one per (image, lookup): an image seen
# through a rotation is projected once and rotated, any other lookup is
# resampled onto a latlong grid first (world.environment_radiance).
_lighting_cache = {}
# Columns of the latlong grid a remapped image is resampled onto: far finer
# than an order-8 SH needs; each cell averages 2×2 lookups, so a small sun
# keeps its flux. About 0.5 s of numpy, once per image and lookup.
_REMAP_WIDTH = 512


def read_world(scene):
    """world.read_scene with the whole sum of Backgrounds, as the SH lighting
    takes it (any Mapping or Vector Rotate lookup, equirectangular or
    mirror-ball images)."""
    return world.read_scene(scene)


def world_lighting(scene, order):
    """(order², 3) SH of the World's radiance (scene-linear), and a note on what
    was used (read_world: the World as penumbra.world reads it, strengths and
    mix weights applied); what cannot be read falls back as the note says."""
    lighting, note, pixel_warning = world_lighting_checked(scene, order)
    return lighting, (f"{note}; {pixel_warning}" if pixel_warning else note)


# The GPU preview's last read of the World, per SH order: read again only
# after forget_reads(), which the preview's handlers call when the depsgraph
# says the World, a node tree or an image changed (an edit, or keyframes and
# drivers at a frame change: Blender tags those IDs then, and no others), when
# a Scene update changed what it was read for (the_scene_changed), on undo and
# load; and every frame while it shows a movie or an image sequence. Reading
# the node tree every frame cost about a tenth of the preview's frame change
# at 100k vertices.
_reads = {}
_read_for = [None]  # what the reads were read for: (World, engine, working space)
# depsgraph.id_type_updated() kinds, and depsgraph.updates ID classes, that
# can change the World's light. Not the Scene: the timeline's frame cursor
# updates it while scrubbing (the_scene_changed looks closer).
RELIGHTING_ID_TYPES = ("WORLD", "NODETREE", "IMAGE")
EDITS_THAT_RELIGHT = ("World", "NodeTree", "Image")


def _reading_context(scene):
    world_block = scene.world
    return (world_block.as_pointer() if world_block is not None else 0, scene.render.engine,
            color.file_working_space())


def lighting_until_edited(scene, order):
    """world_lighting(scene, order)[0], kept until forget_reads()."""
    kept = _reads.get(order)
    if kept is not None and not kept[1]:
        return kept[0]
    lighting, _ = world_lighting(scene, order)
    _reads[order] = (lighting, _shows_moving_image(scene.world))
    _read_for[0] = _reading_context(scene)
    return lighting


def forget_reads():
    _reads.clear()


def the_scene_changed(scene):
    """A Scene update: forgets the reads if the scene's World, render engine
    (its World Output target) or working space is no longer what they were
    read for. True when it did."""
    if _reads and _reading_context(scene) != _read_for[0]:
        _reads.clear()
        return True
    return False


def _shows_moving_image(world_block):
    """Whether the World's nodes, groups included, show a movie or an image sequence."""
    tree = getattr(world_block, "node_tree", None) if world_block is not None else None
    stack, seen = ([tree] if tree is not None else []), set()
    while stack:
        tree = stack.pop()
        for node in tree.nodes:
            image = getattr(node, "image", None)
            if image is not None and image.source in {"MOVIE", "SEQUENCE"}:
                return True
            group = getattr(node, "node_tree", None)
            if group is not None and group.name not in seen:
                seen.add(group.name)
                stack.append(group)
    return False


def _pixel_warning(image, stats):
    """What was wrong with an environment image's pixels ('' when nothing)."""
    bad, negative = stats["non_finite_pixels"], stats["negative_pixels"]
    if not bad and not negative:
        return ""
    parts = []
    if bad:
        parts.append(f"{bad} NaN or infinite pixel(s), lit as black")
    if negative:
        parts.append(f"{negative} pixel(s) with negative values, kept")
    return (f"the World's environment image '{image.name}' has {' and '.join(parts)}; "
            "fix or replace the image for correct lighting")


def world_lighting_checked(scene, order):
    """world_lighting, and a warning about the environment images' pixels
    (NaN, infinite or negative values; '' when none) kept apart from the note."""
    core = native.require()
    lighting = np.zeros((order * order, 3))
    r = read_world(scene)
    warnings = []
    for term in r.terms:
        scale = term.weight * term.strength
        if scale == 0.0:
            continue
        if term.kind == "uniform":
            lighting[0] += term.colour * scale * np.sqrt(4.0 * np.pi)
            continue
        coefficients, warning = _environment_sh(core, term, order)
        lighting += coefficients * scale
        if warning and warning not in warnings:
            warnings.append(warning)
    return lighting, r.note, "; ".join(warnings)


def _lookup_key(term):
    """What, besides the image, decides an environment term's radiance."""
    if term.projection == "EQUIRECTANGULAR" and term.lookup.rotation is not None:
        return ("rotation", term.lookup.rotation.tobytes())
    steps = tuple((a.tobytes(), b.tobytes(), normalize) for a, b, normalize in term.lookup.steps)
    return ("remap", term.projection, term.interpolation, steps)


def _environment_sh(core, term, order):
    """(order², 3) SH of one environment Background at weight and strength 1,
    and its image's pixel warning, cached per image and lookup."""
    image = term.image
    # The working space (Blender 5.0+) changes what the pixels mean, and a
    # float image's pixels themselves.
    key = (image.name, image.filepath, tuple(image.size), image.colorspace_settings.name,
           color.file_working_space(), order, _lookup_key(term))
    cached = _lighting_cache.get(key)
    if cached is None:
        cached = _project_environment(core, term, order)
        if len(_lighting_cache) > 8:  # a few Worlds' images, not every one ever seen
            _lighting_cache.clear()
        _lighting_cache[key] = cached
    return cached


def _project_environment(core, term, order):
    try:
        pixels = world.image_pixels(term.image)
    except world.WorldError as error:
        raise VisibilityInputError(str(error)) from None
    rotation = term.lookup.rotation
    if term.projection == "EQUIRECTANGULAR" and rotation is not None:
        coefficients, stats = core.sh.project_environment(order, pixels, with_stats=True)
        # L(d) = E(R·d): the map's SH turned by world_from_map = Rᵀ.
        if not np.allclose(rotation, np.eye(3)):
            coefficients = core.sh.rotate(coefficients, rotation.T)
        return np.asarray(coefficients), _pixel_warning(term.image, stats)
    # Any other lookup (a Location, a bending or mirroring Scale, a mirror
    # ball): the term's radiance on a latlong grid of world directions, as
    # Blender's Environment Texture looks it up, then projected. Bad pixels
    # are counted on the image itself and lit as black, as the plain path does.
    _, stats = core.sh.project_environment(1, pixels, with_stats=True)
    pixels = np.where(np.isfinite(pixels), pixels, np.float32(0.0))
    grid = world.environment_radiance([_UnitTerm(term)], [pixels], _REMAP_WIDTH)
    coefficients = core.sh.project_environment(order, grid)
    return np.asarray(coefficients), _pixel_warning(term.image, stats)


class _UnitTerm:
    """An environment term's lookup at weight and strength 1 (the cache keeps
    the projection apart from the strength, which may be animated)."""

    def __init__(self, term):
        self.kind, self.lookup, self.projection = term.kind, term.lookup, term.projection
        self.interpolation = term.interpolation
        self.weight = self.strength = 1.0
