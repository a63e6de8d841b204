"""Every label the Penumbra sidebar draws fits its column at Blender's default
sidebar width, measured with Blender's own font (`blf`) at the UI scale.

Neither the bpy module nor `blender -b` has a window, so nothing is laid out
for real. Instead each registered PENUMBRA_PT_ panel's own `draw` (and
`draw_header`) runs against `Recorder`, a stand-in for `bpy.types.UILayout`
that keeps the tree of rows, columns, splits and boxes and every
`prop`/`label`/`operator` call with its text, its real RNA property (UI name,
type, enum items) and the property-split state. The tree is then given the
sidebar's width and divided the way Blender divides it; each text is measured
with `blf.dimensions` against the room its column leaves.

Blender's numbers (pixels at UI scale 1; all scale with the UI scale), from
its source:
- the sidebar opens `UI_SIDEBAR_PANEL_WIDTH` = 220 wide (editors/include/
  UI_interface.h in 3.4 to 4.5; later releases widen it to 280, so a panel that
  fits 220 fits those too; Debian's 3.4 under Xvfb opens it at 229, that is
  220 at Xvfb's 75 dpi);
- the category tabs take `UI_PANEL_CATEGORY_MARGIN_WIDTH` = 1 widget unit (20),
  each side of a panel `UI_PANEL_MARGIN_X` = 0.4 units, and the panel's
  layout is inset by `style->panelspace` = 8 each side (screen/area.c,
  ED_region_panels_layout_ex and ed_panel_draw); sub-panels get the same width;
- a panel's title starts after its arrow (one unit), and a unit is kept for
  the drag handle at its right end (and one for a checkbox in its header);
- with `use_property_split` the label column is `UI_ITEM_PROP_SEP_DIVIDE` =
  0.4 of the row less its decorator column (one unit when
  `use_property_decorate`) (interface_layout.cc, uiItemFullR); its text is
  right-aligned and padded by `UI_TEXT_MARGIN_X` = 0.4 units; a checkbox puts
  its text in the value column, after the box;
- a label's text starts after its icon and that padding, and ends the clip
  margin short of its right edge (as measured on a 3.4 screenshot);
- without it, a text/enum/pointer field's label takes a third of the row
  (ui_item_with_label) and a number field draws its name and value inside;
- a box insets by `style->boxspace` = 5 each side, a non-aligned row spaces
  its items by `style->buttonspacex` = 8 and a split its columns by
  `style->columnspace` = 8 (interface_style.cc); an icon takes one unit; button
  text is clipped `UI_TEXT_CLIP_MARGIN` = 0.25 units from each edge
  (interface_widgets.cc)."""

import json

import blf
import bpy
import pytest

from penumbra import native

# Pixels at UI scale 1 (see the module docstring).
SIDEBAR_WIDTH = 220
WIDGET_UNIT = 20
PANEL_MARGIN_X = 0.4 * WIDGET_UNIT
PANEL_SPACE = 8
BOX_SPACE = 5
BUTTON_SPACE_X = 8
COLUMN_SPACE = 8
PROP_SEP_DIVIDE = 0.4
TEXT_MARGIN_X = 0.4 * WIDGET_UNIT
TEXT_CLIP_MARGIN = 0.25 * WIDGET_UNIT
CHECKBOX_WIDTH = 1.4 * WIDGET_UNIT  # the box and the gap before its text
NUMBER_TEXT_OFFSET = 0.425 * WIDGET_UNIT  # a number field's arrows, each side (widget_numbut_draw)


class _Unset:
    """`text` left out of a call: Blender then uses the property's or operator's own name."""


UNSET = _Unset()


class Node:
    """One layout in the tree: kind is root, column, row, split or box."""

    def __init__(self, kind, align=False, factor=0.0, heading=""):
        self.kind, self.align, self.factor, self.heading = kind, align, factor, heading
        self.children = []


class Item:
    """One prop/label/operator call and the layout state it was made in."""

    def __init__(self, kind, text, split, decorate, heading="", **details):
        self.kind, self.text, self.split, self.decorate, self.heading = kind, text, split, decorate, heading
        self.details = details


class _OperatorProperties:
    """What layout.operator() returns: operator properties can be set on it."""


class Recorder:
    """Stands in for bpy.types.UILayout in a panel's draw(). Only the calls
    modelled here exist; anything else fails the test, so a new kind of call
    in a panel makes someone extend the model instead of going unmeasured."""

    def __init__(self, node, split=False, decorate=True):
        self._node = node
        self.use_property_split = split
        self.use_property_decorate = decorate
        self.alert = self.active = self.enabled = False
        self.scale_x = self.scale_y = 1.0
        self.alignment = "EXPAND"
        self.operator_context = "INVOKE_DEFAULT"

    def _child(self, kind, **options):
        node = Node(kind, **options)
        self._node.children.append(node)
        return Recorder(node, self.use_property_split, self.use_property_decorate)

    def _take_heading(self):
        heading, self._node.heading = self._node.heading, ""
        return heading

    def column(self, align=False, heading="", **_):
        return self._child("column", align=align, heading=heading)

    def row(self, align=False, heading="", **_):
        return self._child("row", align=align, heading=heading)

    def split(self, factor=0.0, align=False):
        return self._child("split", align=align, factor=factor)

    def box(self):
        return self._child("box")

    def _add(self, item):
        self._node.children.append(item)

    def prop(self, data, property, text=UNSET, icon="NONE", expand=False, toggle=-1, icon_only=False, **_):
        rna = data.bl_rna.properties[property]
        self._add(Item("prop", rna.name if text is UNSET else text, self.use_property_split,
                       self.use_property_decorate, self._take_heading(), rna=rna, data=data, icon=icon,
                       expand=expand, toggle=toggle, icon_only=icon_only))

    def label(self, text="", icon="NONE", **_):
        self._add(Item("label", text, self.use_property_split, self.use_property_decorate, icon=icon))

    def operator(self, operator, text=UNSET, icon="NONE", **_):
        module, name = operator.split(".")
        label = getattr(getattr(bpy.ops, module), name).get_rna_type().name
        self._add(Item("operator", label if text is UNSET else text, self.use_property_split,
                       self.use_property_decorate, icon=icon, operator=operator))
        return _OperatorProperties()

    def separator(self, **_):
        pass

    def template_icon(self, **_):
        pass


# --- Blender's geometry -----------------------------------------------------

def ui_scale():
    """The UI scale: the Resolution Scale preference times the pixel size (and,
    with a window, the display's DPI / 72, which Blender keeps in
    system.ui_scale; that is 0 where no window ever opened, as here)."""
    prefs = bpy.context.preferences
    return prefs.system.ui_scale or prefs.view.ui_scale * prefs.system.pixel_size


def panel_width():
    """A panel's full width in the sidebar at its default size."""
    return ui_scale() * (SIDEBAR_WIDTH - WIDGET_UNIT - 2 * PANEL_MARGIN_X)


def layout_width():
    """The width a panel's draw() lays out in."""
    return panel_width() - 2 * ui_scale() * PANEL_SPACE


class Measure:
    """Text widths with the UI's fonts at the UI scale."""

    def __init__(self):
        style = bpy.context.preferences.ui_styles[0]
        # Blender 3.x draws labels in their own style ("Widget Label"); 4.0 merged it into "Widget".
        label_style = getattr(style, "widget_label", None) or style.widget
        self.points = {"widget": style.widget.points, "label": label_style.points, "title": style.panel_title.points}

    def __call__(self, text, font="widget"):
        # No dpi argument: 3.4 deprecates it (always 72, a pixel a point), 4.0 removed it.
        blf.size(0, self.points[font] * ui_scale())
        return blf.dimensions(0, text)[0]


def _shares(node, width):
    """The widths node's children get."""
    s = ui_scale()
    n = len(node.children)
    if node.kind in ("root", "column"):
        return [width] * n
    if node.kind == "box":
        return [width - 2 * s * BOX_SPACE] * n
    gap = 0 if node.align else s * (BUTTON_SPACE_X if node.kind == "row" else COLUMN_SPACE)
    free = width - gap * (n - 1)
    if node.kind == "split" and node.factor > 0 and n > 1:
        first = free * node.factor
        return [first] + [(free - first) / (n - 1)] * (n - 1)
    return [free / n] * n


def _room(item, width):
    """[(what, text, room in px, font)] for one call at one width."""
    s, unit = ui_scale(), ui_scale() * WIDGET_UNIT
    icon = unit if item.details.get("icon", "NONE") != "NONE" else 0
    if item.kind == "label":
        return [("label", item.text, width - s * (TEXT_MARGIN_X + TEXT_CLIP_MARGIN) - icon, "widget")]
    if item.kind == "operator":
        return [("button", item.text, width - 2 * s * TEXT_CLIP_MARGIN - icon, "widget")]
    return _prop_room(item, width, s, unit, icon)


def _prop_room(item, width, s, unit, icon):
    rna, d = item.details["rna"], item.details
    if d["icon_only"]:
        return []
    checkbox = rna.type == "BOOLEAN" and d["toggle"] != 1 and d["icon"] == "NONE"
    enum_items = [e.name for e in rna.enum_items] if rna.type == "ENUM" and not d["expand"] else []
    pad = s * TEXT_MARGIN_X
    out = []
    if item.split:
        row = width - (unit if item.decorate else 0)
        label_column = int(PROP_SEP_DIVIDE * row)
        value_column = row - label_column
        if item.heading:
            out.append(("heading", item.heading, label_column - pad, "label"))
        if checkbox:
            out.append(("checkbox", item.text, value_column - s * CHECKBOX_WIDTH, "widget"))
        elif item.text:
            out.append(("split label", item.text, label_column - pad, "label"))
        else:
            value_column = row  # no label: the field takes the whole row
        out += [("menu item", name, value_column - pad - unit, "widget") for name in enum_items]
        return out
    if checkbox:
        return [("checkbox", item.text, width - s * CHECKBOX_WIDTH, "widget")]
    if rna.type in ("INT", "FLOAT") and not getattr(rna, "is_array", False) and item.text:
        value = getattr(d["data"], rna.identifier)
        shown = str(value) if rna.type == "INT" else f"{value:.{rna.precision}f}"
        # "Name: value" inside one field, between its arrows.
        room = width - 2 * s * (NUMBER_TEXT_OFFSET + TEXT_CLIP_MARGIN) - Measure()(": " + shown)
        return [("number field", item.text, room, "widget")]
    if rna.type == "BOOLEAN":
        return [("button", item.text, width - 2 * s * TEXT_CLIP_MARGIN - icon, "widget")]
    if item.text:
        out.append(("field label", item.text, width / 3 - pad, "label"))
    out += [("menu item", name, 2 * width / 3 - pad - unit, "widget") for name in enum_items]
    return out


def rooms(node, width):
    for child, share in zip(node.children, _shares(node, width)):
        if isinstance(child, Node):
            yield from rooms(child, share)
        else:
            yield from _room(child, share)


# --- Running the panels -------------------------------------------------------

class _PanelSelf:
    """The `self` a Panel's draw() sees: only its layout."""

    def __init__(self, layout):
        self.layout = layout


def penumbra_panels():
    names = sorted(n for n in dir(bpy.types) if n.startswith("PENUMBRA_PT_"))
    return [getattr(bpy.types, n) for n in names]


def assert_all_fit(panel_classes, context):
    problems = too_long(panel_classes, context)
    assert not problems, "these texts do not fit:\n" + "\n".join(problems)


def too_long(panel_classes, context):
    """Every text that does not fit, as 'PANEL: what "text" needs N px, has M'."""
    measure, problems = Measure(), []
    header_room = panel_width() - 2 * ui_scale() * WIDGET_UNIT - ui_scale() * TEXT_MARGIN_X

    def check(where, what, text, room, font):
        need = measure(text, font)
        if text and need > room:
            problems.append(f'{where}: {what} "{text}" needs {need:.0f} px, has {room:.0f}')

    for cls in panel_classes:
        if hasattr(cls, "poll") and not cls.poll(context):
            continue
        header_checkbox = 0
        if hasattr(cls, "draw_header"):
            # A header's own widgets (a checkbox) take a unit before the label and carry no text.
            header_checkbox = ui_scale() * WIDGET_UNIT
            header = Node("root")
            cls.draw_header(_PanelSelf(Recorder(header)), context)
            for what, text, _, font in rooms(header, layout_width()):
                check(cls.__name__, f"header {what}", text, 0, font)
        check(cls.__name__, "header", cls.bl_label, header_room - header_checkbox, "title")
        root = Node("root")
        cls.draw(_PanelSelf(Recorder(root)), context)
        for what, text, room, font in rooms(root, layout_width()):
            check(cls.__name__, what, text, room, font)
    return problems


# --- Scenes that reach every branch of the panels -----------------------------

REPORT = {"frames": 24, "rays": 256, "lobes": 2, "model_bytes": 1_234_567, "dense_bytes": 9_876_543,
          "seconds_bake": 12.3, "seconds_fit": 4.5, "zh_fit": {"sh_rms": 0.0123},
          "active_joints": ["upper_arm.L", "forearm.L", "upper_arm.R", "forearm.R", "spine"],
          "holdout_frames": [20, 21, 22], "model_holdout": {"ao_mean_abs": 0.0111}}
LONG_STATUS = ("the visibility model /home/artist/projects/penumbra/character_visibility_model.pzv was "
               "baked for 812 vertices but the mesh now has 7966; bake again")


def build_scene(brdf, world):
    """A skinned mesh (active), its armature, and the World set up as asked."""
    scene = bpy.context.scene
    armature = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    mesh = bpy.data.meshes.new("Body")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    body = bpy.data.objects.new("Body", mesh)
    body.modifiers.new("Armature", "ARMATURE").object = armature
    for obj in (armature, body):
        scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = body
    settings = body.penumbra_visibility
    settings.brdf = brdf
    settings.report = json.dumps(REPORT)
    settings.status = LONG_STATUS
    scene_settings = scene.penumbra.visibility
    scene_settings["gpu_preview"] = True  # without its update: no GPU here
    scene_settings.gpu_preview_status = "the GPU preview needs a model of order 3 or less; this one is order 4"
    scene.world = _world(world)
    return scene


def _world(kind):
    if kind == "none":
        return None
    world = bpy.data.worlds.new("World")
    if bpy.app.version < (5, 0, 0):  # 5.0 always uses nodes, and deprecates the switch
        world.use_nodes = True
    if kind == "environment":
        tree = world.node_tree
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.new("studio_small_09_4k_with_a_long_name.exr", 8, 4, float_buffer=True)
        tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    return world


def light_rig_states(scene):
    """The light rig's settings that change what it draws: empty source, and a long last report."""
    rig = scene.penumbra.light_rig
    rig.last_report = ("64 lights over 240 frame(s) in 'Penumbra Light Rig'; JSON: /home/artist/projects/"
                       "penumbra/shots/sh010/penumbra_light_rig.json; replaced 3 NaN, 0 Inf and 12 negative "
                       "pixel values by 0")
    return rig


SCENES = {
    "phong, environment World, empty source": ("PHONG", "environment", ""),
    "translucent, plain World, video source": ("TRANSLUCENT", "plain", "/footage/shot_010/sky_timelapse_0001.exr"),
    "diffuse, no World": ("DIFFUSE", "none", ""),
}


@pytest.mark.parametrize("scale", (1.0, 1.25))
@pytest.mark.parametrize("name", list(SCENES))
def test_every_label_fits_its_column_at_the_default_sidebar_width(addon, name, scale, monkeypatch):
    # The font's hinting does not scale exactly with the UI: check a second scale.
    monkeypatch.setattr(bpy.context.preferences.view, "ui_scale", scale)
    brdf, world, source = SCENES[name]
    scene = build_scene(brdf, world)
    light_rig_states(scene).filepath = source
    assert_all_fit(penumbra_panels(), bpy.context)


def test_every_label_fits_with_no_mesh_selected(addon):
    build_scene("DIFFUSE", "plain")
    bpy.context.view_layer.objects.active = bpy.data.objects["Rig"]
    assert_all_fit(penumbra_panels(), bpy.context)


def test_the_missing_core_message_fits(addon, monkeypatch):
    build_scene("DIFFUSE", "plain")
    monkeypatch.setattr(native, "module", None)
    monkeypatch.setattr(native, "load_error", ImportError(
        "/home/artist/.config/blender/3.4/scripts/addons/penumbra/_penumbra.cpython-311-x86_64-linux-gnu.so: "
        "cannot open shared object file: No such file or directory"))
    assert_all_fit([bpy.types.PENUMBRA_PT_main], bpy.context)


class _CrampedPanel:
    """The Bake rows the visibility panel drew before issue #11: three number
    fields in one row inside a box, and a pointer field with its label."""

    bl_label = "Cramped"

    def draw(self, context):
        s = context.active_object.penumbra_visibility
        box = self.layout.box()
        row = box.row(align=True)
        for name in ("frame_start", "frame_end", "frame_step"):
            row.prop(s, name)
        box.prop(s, "occluders")
        row = box.row(align=True)
        row.operator("penumbra.apply_visibility", icon="SHADING_RENDERED")
        row.operator("penumbra.setup_material", icon="MATERIAL")


def test_the_model_catches_the_labels_blender_cut_before(addon):
    # Under Xvfb these showed as "St 1 | 24 | St 1", "Occl…" and "Apply Vi…".
    build_scene("DIFFUSE", "plain")
    problems = "\n".join(too_long([_CrampedPanel], bpy.context))
    for text in ('"Start"', '"Step"', '"Occluders"', '"Apply Visibility"', '"Set Up Material"'):
        assert text in problems
