"""How many sun shadows EEVEE Next's shadow pool holds (Blender 4.2+).

EEVEE Next keeps the shadow-map pages of every light in one pool of
`scene.eevee.shadow_pool_size` MB. A frame that needs more pages prints
"Shadow buffer full, may result in missing shadows" and drops some: a sun
whose shadow is dropped lights the ground inside it. The pool is the
user's render setting; the rig only says when its suns may not fit
(docs/lights.md, "EEVEE Next's shadow pool")."""

import bpy

from . import rig_objects

PAGE_MB = 0.25  # one page: 256 x 256 texels of 32 bits, so the factory 512 MB holds 2048 pages
# A sun's shadow took 43-61 pages in every scene of the EEVEE benchmark, at
# 96x72 and at 960x720 alike (it follows the view's depth, not its pixels);
# rounded up, so the factory pool is said to hold 32 suns.
PAGES_PER_SUN = 64


def sun_capacity(scene):
    """About how many sun shadows the scene's pool holds; None before 4.2
    (EEVEE Legacy has no pool, but a limit of 8 shadowed suns)."""
    if bpy.app.version < (4, 2, 0):
        return None
    return int(float(scene.eevee.shadow_pool_size) / PAGE_MB) // PAGES_PER_SUN


def shadowed_suns(collection):
    """The suns of a rig collection that cast a shadow."""
    if collection is None:
        return 0
    return sum(1 for o in collection.all_objects if o.type == "LIGHT" and o.data.use_shadow)


def overflow_warning(scene, target_renderer, shadowed):
    """What to tell the user when `shadowed` suns of a rig for EEVEE Next
    may not fit its shadow pool; '' when they fit or another renderer draws it."""
    capacity = sun_capacity(scene)
    if capacity is None or shadowed <= capacity or not rig_objects.targets_eevee(target_renderer, scene):
        return ""
    return (f"{shadowed} suns cast shadows; EEVEE's shadow pool ({scene.eevee.shadow_pool_size} MB) holds about "
            f"{capacity}: raise Shadows Pool Size (Render Properties, Performance) or set a Shadow Budget")
