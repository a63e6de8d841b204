"""build_light_rig's target renderer (docs/lights.md, "Suns in EEVEE"): the
model the fit minimises against and the strength each sun is written with
follow the renderer the rig is for, the scene's engine by default."""

import bpy
import numpy as np

from lights_scenes import core_module, sky_and_sun, write_map


def _eevee_engine():
    return "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"


def _suns(scene):
    from penumbra.lights import rig_objects
    return sorted((o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"),
                  key=lambda o: o[rig_objects.INDEX_KEY])


def _build(path, tmp_path, **kw):
    r = bpy.ops.penumbra.build_light_rig(filepath=path, count=16, json_path=str(tmp_path / "rig.json"), **kw)
    assert r == {"FINISHED"}, r


def test_the_scenes_engine_picks_the_sun_model_and_the_strengths(addon, tmp_path):
    from penumbra.lights import rig_objects
    scene = addon
    lights = core_module().lights
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(radius=0.6))
    eevee_model = lights.sun_model_for_renderer(*bpy.app.version[:2], True, True)
    assert eevee_model.name == ("EEVEE_LEGACY" if bpy.app.version < (4, 2, 0) else "EEVEE_NEXT_SHADOWED")
    picked = {}
    for engine in ("CYCLES", _eevee_engine()):
        scene.render.engine = engine
        _build(path, tmp_path)
        suns = _suns(scene)
        model = rig_objects.sun_model(eevee=engine != "CYCLES")
        angle = np.array([o.data.angle for o in suns])
        assert sum(o.data.energy for o in suns) > 0
        picked[engine] = (model.name, np.array([o.data.energy for o in suns]), angle)
    assert picked["CYCLES"][0] != picked[_eevee_engine()][0]
    # The same map fitted for EEVEE writes other suns than for Cycles.
    assert not np.allclose(picked["CYCLES"][1], picked[_eevee_engine()][1], rtol=1e-3)


def test_an_explicit_target_overrides_the_scenes_engine(addon, tmp_path):
    scene = addon
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(radius=0.6))
    scene.render.engine = "CYCLES"
    _build(path, tmp_path, target_renderer="EEVEE")
    for_eevee = [o.data.energy for o in _suns(scene)]
    scene.render.engine = _eevee_engine()
    _build(path, tmp_path)
    np.testing.assert_allclose([o.data.energy for o in _suns(scene)], for_eevee, rtol=1e-6)
    _build(path, tmp_path, target_renderer="CYCLES")
    assert not np.allclose([o.data.energy for o in _suns(scene)], for_eevee, rtol=1e-3)


def _output_panel_labels(context):
    """The texts of the labels the Output sub-panel draws (its draw() run on
    test_panel_labels' recording layout)."""
    from test_panel_labels import Node, Recorder, _PanelSelf
    root = Node("root")
    bpy.types.PENUMBRA_PT_light_rig_output.draw(_PanelSelf(Recorder(root)), context)
    texts, nodes = [], [root]
    while nodes:
        node = nodes.pop()
        for child in getattr(node, "children", ()):
            nodes.append(child)
            if getattr(child, "kind", "") == "label":
                texts.append(child.text)
    return " ".join(texts)


def test_the_panel_says_when_eevee_next_gives_the_rig_no_bounce_light(addon):
    # docs/lights.md, "Ray tracing gives back the bounce light": without Ray
    # Tracing, EEVEE Next's rig lacks the light Cycles bounces between objects.
    scene, s = addon, addon.penumbra.light_rig
    scene.render.engine = _eevee_engine()
    for target, tracing, shown in (("SCENE", False, True), ("EEVEE", False, True), ("CYCLES", False, False),
                                   ("SCENE", True, False), ("EEVEE", True, False)):
        s.target_renderer = target
        if bpy.app.version >= (4, 2, 0):
            scene.eevee.use_raytracing = tracing
        expected = shown and bpy.app.version >= (4, 2, 0)  # EEVEE Legacy has no Ray Tracing to turn on
        assert ("Ray Tracing is off" in _output_panel_labels(bpy.context)) == expected, (target, tracing)
    scene.render.engine = "CYCLES"
    s.target_renderer = "SCENE"
    if bpy.app.version >= (4, 2, 0):
        scene.eevee.use_raytracing = False
    assert "Ray Tracing is off" not in _output_panel_labels(bpy.context)


def test_a_rig_for_eevee_next_says_when_its_shadows_may_not_fit_the_shadow_pool(addon, tmp_path):
    # docs/lights.md, "EEVEE Next's shadow pool": 64 shadowed suns overflowed
    # the factory 512 MB pool in every scene of the EEVEE benchmark, and
    # EEVEE dropped shadows; 32 fit.
    from penumbra.lights import shadow_pool
    scene, s = addon, addon.penumbra.light_rig
    scene.render.engine = _eevee_engine()
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(radius=0.6))
    said = "EEVEE's shadow pool"
    for count, budget, shown in ((40, 0, True), (32, 0, False), (40, 8, False)):
        r = bpy.ops.penumbra.build_light_rig(filepath=path, count=count, shadow_budget=budget,
                                             json_path=str(tmp_path / "rig.json"))
        assert r == {"FINISHED"}, r
        if budget == 0 and bpy.app.version >= (4, 2, 0):  # Legacy shadows 8 (test_lights.py)
            assert shadow_pool.shadowed_suns(s.collection) == count
        expected = shown and bpy.app.version >= (4, 2, 0)  # EEVEE Legacy has no pool (its limit: 8 suns)
        assert (said in _output_panel_labels(bpy.context)) == expected, (count, budget)
        assert (said in s.last_report) == expected, (count, budget, s.last_report)
    if bpy.app.version >= (4, 2, 0):
        bpy.ops.penumbra.build_light_rig(filepath=path, count=40, json_path=str(tmp_path / "rig.json"))
        assert "shadow pool (512 MB) holds about 32" in _output_panel_labels(bpy.context)
        scene.eevee.shadow_pool_size = "1024"  # the user's fix: the pool then holds 64
        assert said not in _output_panel_labels(bpy.context)
        scene.eevee.shadow_pool_size = "512"
        s.target_renderer = "CYCLES"  # Cycles has no pool
        assert said not in _output_panel_labels(bpy.context)
