"""What every panel of the "Penumbra" sidebar tab shares: where it lives,
and messages that fit. A long status or report is wrapped onto several
labels instead of being cut to "Lighting: u…ound colour" by Blender; widths
are measured with Blender's own UI font at the UI scale, against the
sidebar's width less what Blender spends around a panel's layout."""

import re

import blf

# Pixels at UI scale 1. The sidebar opens 220 wide (UI_SIDEBAR_PANEL_WIDTH in
# Blender 3.4 to 4.5); a panel's layout loses the category tabs (20), the
# panel margins (2 × 8) and the panel's inset (2 × 8).
SIDEBAR_WIDTH = 220
AROUND_LAYOUT = 20 + 2 * 8 + 2 * 8
# A label's text: after its icon (20) and text padding (8), up to the clip
# margin at its right end (5), with 2 to spare for Blender's rounding.
ICON = 20
AROUND_LABEL = ICON + 8 + 5 + 2
ELLIPSIS = "\u2026"


class SidebarPanel:
    """The Penumbra tab of the 3D Viewport's sidebar."""
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Penumbra"


class ToolSection(SidebarPanel):
    """One tool's section: closed until the user opens it."""
    bl_parent_id = "PENUMBRA_PT_main"
    bl_options = {"DEFAULT_CLOSED"}


def ui_scale(context):
    """Blender's UI scale: the Resolution Scale preference times the display's
    DPI / 72 (Xvfb reports 75) and pixel size; 0 where no window ever opened
    (a script, the bpy module), and there the preference alone."""
    prefs = context.preferences
    return prefs.system.ui_scale or prefs.view.ui_scale * prefs.system.pixel_size


def text_width(context, text):
    """Width in pixels of `text` in the UI's widget font."""
    style = context.preferences.ui_styles[0]
    size = style.widget.points * ui_scale(context)
    # No dpi argument: 3.4 deprecates it (always 72, a pixel a point), 4.0 removed it.
    blf.size(0, size)
    return blf.dimensions(0, text)[0]


def label_room(context, icon=True):
    """Pixels a label's text has in the panel, in the sidebar as it is now
    (or at its default width while no sidebar is drawing, as in a script)."""
    scale = ui_scale(context)
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.type == "UI" else SIDEBAR_WIDTH * scale
    return width - (AROUND_LAYOUT + AROUND_LABEL - (0 if icon else ICON)) * scale


def wrap(context, text, room):
    """`text` as lines no wider than `room` pixels: clauses ("; ") start a new
    line, words wrap, and a word wider than a line (a path) is broken."""
    lines = []
    for clause in text.split("; "):
        line = ""
        for word in clause.split():
            candidate = f"{line} {word}" if line else word
            if text_width(context, candidate) <= room:
                line = candidate
                continue
            if line:
                lines.append(line)
            line = word
            while text_width(context, line) > room and len(line) > 1:
                cut = _longest_prefix(context, line, room)
                lines.append(line[:cut])
                line = line[cut:]
        if line:
            lines.append(line)
    return lines


def _longest_prefix(context, word, room):
    """How much of `word` fits `room`, ending after a separator (/ _ - .) when one is near."""
    cut = len(word) - 1
    while cut > 1 and text_width(context, word[:cut]) > room:
        cut -= 1
    separator = max(word.rfind(mark, 0, cut) for mark in "/\\_-.")
    return separator + 1 if separator >= cut // 2 else cut


# A path below two or more folders (POSIX or Windows): shown by its file name.
_PATH = re.compile(r"""(?<![\w.])(?:~|[A-Za-z]:)?(?:[\\/][^\\/\s;'"]+){3,}""")


def short_paths(text):
    """`text` with each long path cut to its file name: '…/model.pzv'."""
    return _PATH.sub(lambda match: ELLIPSIS + "/" + re.split(r"[\\/]", match.group(0))[-1], text)


def draw_wrapped(layout, context, text, icon="NONE", max_lines=8):
    """`text` as labels in `layout`, the first with `icon` (the others with a
    blank one, so the text lines up), paths by their file name; past
    `max_lines` the last line ends in an ellipsis (the whole text stays in the
    property, or in the operator's report)."""
    room = label_room(context, icon != "NONE")
    lines = wrap(context, short_paths(text), room)
    if len(lines) > max_lines:
        lines = lines[:max_lines]
        lines[-1] = _with_ellipsis(context, lines[-1], room)
    column = layout.column(align=True)
    following = "NONE" if icon == "NONE" else "BLANK1"
    for number, line in enumerate(lines):
        column.label(text=line, icon=icon if number == 0 else following)
    return column


def _with_ellipsis(context, line, room):
    while line and text_width(context, line + ELLIPSIS) > room:
        line = line[:-1]
    return line.rstrip() + ELLIPSIS
