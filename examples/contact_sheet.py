"""Contact sheets for the demo: pictures in labelled rows, text drawn with a
small bitmap font, written as PNG. Pure numpy (any Python Blender runs);
the file is written by `_penumbra.image.write_png16`.

    sheet = Sheet("Visibility: held-out poses")
    sheet.row([Tile(reference, ["Cycles AO"]), Tile(result, ["Penumbra", "mean |Δ| 0.005"])])
    sheet.write("out/visibility-sheet.png")

Pictures are display-referred RGB floats in [0, 1], (H, W, 3), top row first."""

import os

import numpy as np

# A 5×7 bitmap font written for this file (public domain): each glyph is up to
# nine rows of five columns, '#' = ink; rows 0–6 sit on the baseline, rows 7–8
# are descenders. Characters not listed are drawn as '?'.
_GLYPHS = {
    " ": "",
    "A": ".###. #...# #...# #...# ##### #...# #...#",
    "B": "####. #...# #...# ####. #...# #...# ####.",
    "C": ".###. #...# #.... #.... #.... #...# .###.",
    "D": "###.. #..#. #...# #...# #...# #..#. ###..",
    "E": "##### #.... #.... ####. #.... #.... #####",
    "F": "##### #.... #.... ####. #.... #.... #....",
    "G": ".###. #...# #.... #.### #...# #...# .####",
    "H": "#...# #...# #...# ##### #...# #...# #...#",
    "I": ".###. ..#.. ..#.. ..#.. ..#.. ..#.. .###.",
    "J": "..### ...#. ...#. ...#. ...#. #..#. .##..",
    "K": "#...# #..#. #.#.. ##... #.#.. #..#. #...#",
    "L": "#.... #.... #.... #.... #.... #.... #####",
    "M": "#...# ##.## #.#.# #.#.# #...# #...# #...#",
    "N": "#...# #...# ##..# #.#.# #..## #...# #...#",
    "O": ".###. #...# #...# #...# #...# #...# .###.",
    "P": "####. #...# #...# ####. #.... #.... #....",
    "Q": ".###. #...# #...# #...# #.#.# #..#. .##.#",
    "R": "####. #...# #...# ####. #.#.. #..#. #...#",
    "S": ".#### #.... #.... .###. ....# ....# ####.",
    "T": "##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#..",
    "U": "#...# #...# #...# #...# #...# #...# .###.",
    "V": "#...# #...# #...# #...# #...# .#.#. ..#..",
    "W": "#...# #...# #...# #.#.# #.#.# #.#.# .#.#.",
    "X": "#...# #...# .#.#. ..#.. .#.#. #...# #...#",
    "Y": "#...# #...# .#.#. ..#.. ..#.. ..#.. ..#..",
    "Z": "##### ....# ...#. ..#.. .#... #.... #####",
    "a": "..... ..... .###. ....# .#### #...# .####",
    "b": "#.... #.... #.##. ##..# #...# #...# ####.",
    "c": "..... ..... .###. #.... #.... #...# .###.",
    "d": "....# ....# .##.# #..## #...# #...# .####",
    "e": "..... ..... .###. #...# ##### #.... .###.",
    "f": "..##. .#..# .#... ###.. .#... .#... .#...",
    "g": "..... ..... .#### #...# #...# #...# .#### ....# .###.",
    "h": "#.... #.... #.##. ##..# #...# #...# #...#",
    "i": "..#.. ..... .##.. ..#.. ..#.. ..#.. .###.",
    "j": "...#. ..... ..##. ...#. ...#. ...#. ...#. #..#. .##..",
    "k": "#.... #.... #..#. #.#.. ##... #.#.. #..#.",
    "l": ".##.. ..#.. ..#.. ..#.. ..#.. ..#.. .###.",
    "m": "..... ..... ##.#. #.#.# #.#.# #.#.# #.#.#",
    "n": "..... ..... #.##. ##..# #...# #...# #...#",
    "o": "..... ..... .###. #...# #...# #...# .###.",
    "p": "..... ..... ####. #...# #...# #...# ####. #.... #....",
    "q": "..... ..... .#### #...# #...# #...# .#### ....# ....#",
    "r": "..... ..... #.##. ##..# #.... #.... #....",
    "s": "..... ..... .###. #.... .###. ....# ####.",
    "t": ".#... .#... ###.. .#... .#... .#..# ..##.",
    "u": "..... ..... #...# #...# #...# #..## .##.#",
    "v": "..... ..... #...# #...# #...# .#.#. ..#..",
    "w": "..... ..... #...# #...# #.#.# #.#.# .#.#.",
    "x": "..... ..... #...# .#.#. ..#.. .#.#. #...#",
    "y": "..... ..... #...# #...# #...# #...# .#### ....# .###.",
    "z": "..... ..... ##### ...#. ..#.. .#... #####",
    "0": ".###. #...# #..## #.#.# ##..# #...# .###.",
    "1": "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###.",
    "2": ".###. #...# ....# ...#. ..#.. .#... #####",
    "3": "##### ...#. ..#.. ...#. ....# #...# .###.",
    "4": "...#. ..##. .#.#. #..#. ##### ...#. ...#.",
    "5": "##### #.... ####. ....# ....# #...# .###.",
    "6": "..##. .#... #.... ####. #...# #...# .###.",
    "7": "##### ....# ...#. ..#.. .#... .#... .#...",
    "8": ".###. #...# #...# .###. #...# #...# .###.",
    "9": ".###. #...# #...# .#### ....# ...#. .##..",
    ".": "..... ..... ..... ..... ..... .##.. .##..",
    ",": "..... ..... ..... ..... ..... .##.. .##.. ..#.. .#...",
    ":": "..... .##.. .##.. ..... .##.. .##.. .....",
    ";": "..... .##.. .##.. ..... .##.. .##.. ..#.. .#...",
    "-": "..... ..... ..... .###. ..... ..... .....",
    "+": "..... ..#.. ..#.. ##### ..#.. ..#.. .....",
    "=": "..... ..... ##### ..... ##### ..... .....",
    "(": "...#. ..#.. .#... .#... .#... ..#.. ...#.",
    ")": ".#... ..#.. ...#. ...#. ...#. ..#.. .#...",
    "[": ".###. .#... .#... .#... .#... .#... .###.",
    "]": ".###. ...#. ...#. ...#. ...#. ...#. .###.",
    "/": "....# ....# ...#. ..#.. .#... #.... #....",
    "%": "##... ##..# ...#. ..#.. .#... #..## ...##",
    "|": "..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#..",
    "_": "..... ..... ..... ..... ..... ..... #####",
    "<": "...#. ..#.. .#... #.... .#... ..#.. ...#.",
    ">": ".#... ..#.. ...#. ....# ...#. ..#.. .#...",
    "?": ".###. #...# ....# ...#. ..#.. ..... ..#..",
    "!": "..#.. ..#.. ..#.. ..#.. ..#.. ..... ..#..",
    "#": ".#.#. .#.#. ##### .#.#. ##### .#.#. .#.#.",
    "*": "..... ..#.. #.#.# .###. #.#.# ..#.. .....",
    "'": "..#.. ..#.. .#...",
    '"': ".#.#. .#.#. .#.#.",
    "×": "..... #...# .#.#. ..#.. .#.#. #...# .....",
    "·": "..... ..... ..... .##.. .##.. ..... .....",
    "°": ".##.. #..#. #..#. .##.. ..... ..... .....",
    "Δ": "..#.. ..#.. .#.#. .#.#. #...# #...# #####",
    "σ": "..... ..... .#### #..#. #...# #...# .###.",
    "→": "..... ..#.. ...#. ##### ...#. ..#.. .....",
    "≈": "..... .#... #.#.# ...#. .#... #.#.# ...#.",
    "≤": "...#. ..#.. .#... ..#.. ...#. ..... #####",
}
GLYPH_WIDTH, GLYPH_HEIGHT, ASCENT = 5, 9, 7


def _glyph_masks():
    masks = {}
    for char, rows in _GLYPHS.items():
        mask = np.zeros((GLYPH_HEIGHT, GLYPH_WIDTH), dtype=bool)
        for y, row in enumerate(rows.split()):
            mask[y] = [c == "#" for c in row]
        masks[char] = mask
    return masks


_MASKS = _glyph_masks()


def text_size(text, scale=2):
    """(width, height) in pixels of one line of text."""
    return max(len(text) * (GLYPH_WIDTH + 1) - 1, 0) * scale, GLYPH_HEIGHT * scale


def draw_text(canvas, x, y, text, scale=2, colour=(1.0, 1.0, 1.0)):
    """Draws one line into canvas (H, W, 3) with its top-left corner at (x, y);
    ink that falls outside the canvas is dropped."""
    colour = np.asarray(colour, dtype=canvas.dtype)
    for i, char in enumerate(text):
        mask = _MASKS.get(char, _MASKS["?"])
        big = np.repeat(np.repeat(mask, scale, axis=0), scale, axis=1)
        gx = x + i * (GLYPH_WIDTH + 1) * scale
        y0, y1 = max(y, 0), min(y + big.shape[0], canvas.shape[0])
        x0, x1 = max(gx, 0), min(gx + big.shape[1], canvas.shape[1])
        if y0 < y1 and x0 < x1:
            region = canvas[y0:y1, x0:x1]
            region[big[y0 - y:y1 - y, x0 - gx:x1 - gx]] = colour


# --- Pictures --------------------------------------------------------------

def grey(values):
    """(H, W) → (H, W, 3)."""
    return np.repeat(np.asarray(values, dtype=np.float32)[..., None], 3, axis=-1)


# A perceptually ordered dark-to-bright ramp for differences (stops in
# display space, close to matplotlib's "inferno").
_HEAT = np.array([(0.0, 0.0, 0.02), (0.26, 0.04, 0.41), (0.58, 0.15, 0.40), (0.87, 0.32, 0.23),
                  (0.98, 0.65, 0.04), (0.99, 1.0, 0.64)], dtype=np.float32)


def heat(values, vmax):
    """Scalars (H, W) in [0, vmax] → display RGB (H, W, 3) along the heat ramp."""
    t = np.clip(np.asarray(values, dtype=np.float32) / vmax, 0.0, 1.0) * (len(_HEAT) - 1)
    k = np.minimum(t.astype(np.int32), len(_HEAT) - 2)
    f = (t - k)[..., None]
    return (1.0 - f) * _HEAT[k] + f * _HEAT[k + 1]


def over(rgb, alpha, background):
    """Composites display RGB with coverage alpha (H, W) over a flat colour."""
    a = np.clip(np.asarray(alpha, dtype=np.float32), 0.0, 1.0)[..., None]
    return rgb * a + np.asarray(background, dtype=np.float32) * (1.0 - a)


def enlarge(image, factor):
    """Nearest-neighbour enlargement by an integer factor (pixels stay visible)."""
    return np.repeat(np.repeat(image, factor, axis=0), factor, axis=1)


def _area_weights(size_in, size_out):
    """(size_out, size_in) matrix averaging the input cells each output cell covers."""
    edges = np.linspace(0.0, size_in, size_out + 1)
    lo, hi = edges[:-1, None], edges[1:, None]
    cells = np.arange(size_in)[None, :]
    overlap = np.clip(np.minimum(hi, cells + 1) - np.maximum(lo, cells), 0.0, None)
    return (overlap / overlap.sum(axis=1, keepdims=True)).astype(np.float32)


def resize(image, width):
    """Area-averaged resize to `width` (height keeps the aspect ratio)."""
    h, w = image.shape[:2]
    height = max(1, int(round(h * width / w)))
    rows, cols = _area_weights(h, height), _area_weights(w, width)
    return np.einsum("yh,hwc,xw->yxc", rows, image.astype(np.float32), cols, optimize=True)


def outline(image, x0, y0, x1, y1, colour=(1.0, 1.0, 1.0), thickness=2):
    """Draws a rectangle's outline into image (in place) and returns it."""
    c = np.asarray(colour, dtype=np.float32)
    image[y0:y0 + thickness, x0:x1] = c
    image[y1 - thickness:y1, x0:x1] = c
    image[y0:y1, x0:x0 + thickness] = c
    image[y0:y1, x1 - thickness:x1] = c
    return image


def heat_legend(vmax, width=240, label="|Δ|", scale=2):
    """A colour bar for heat(): the ramp with '0' and vmax written under it."""
    bar_h = 14
    _, text_h = text_size("0", scale)
    legend = np.full((bar_h + 4 + text_h, width, 3), BACKGROUND, dtype=np.float32)
    legend[:bar_h] = heat(np.linspace(0.0, vmax, width)[None, :].repeat(bar_h, 0), vmax)
    draw_text(legend, 0, bar_h + 4, f"{label} 0", scale, TEXT)
    end = f"{vmax:g}"
    draw_text(legend, width - text_size(end, scale)[0], bar_h + 4, end, scale, TEXT)
    return legend


# --- Sheets ----------------------------------------------------------------

BACKGROUND = (0.13, 0.13, 0.14)
TEXT = (0.92, 0.92, 0.92)
DIM = (0.62, 0.64, 0.68)
MARGIN, GAP, LINE = 20, 14, 6


class Tile:
    """A picture with label lines above it (the first line bright, the rest dim)."""

    def __init__(self, image, lines=()):
        self.image = np.asarray(image, dtype=np.float32)[..., :3]
        self.lines = [line for line in lines if line]


class Sheet:
    """Rows of tiles under a title, at least `min_width` pixels wide."""

    def __init__(self, title, subtitle="", min_width=1200, scale=2):
        self.title, self.subtitle, self.min_width, self.scale = title, subtitle, min_width, scale
        self.rows = []

    def row(self, tiles, caption=""):
        self.rows.append((caption, tiles))

    def _slot_width(self, tile):
        """A tile's column: its picture, or its widest label if wider."""
        return max([tile.image.shape[1]] + [text_size(line, self.scale)[0] for line in tile.lines])

    def render(self):
        line_h = text_size("A", self.scale)[1] + LINE
        title_h = text_size("A", 3)[1] + LINE + (line_h if self.subtitle else 0)
        width = max(text_size(self.title, 3)[0], text_size(self.subtitle, self.scale)[0])
        layouts, height = [], MARGIN + title_h + GAP
        for caption, tiles in self.rows:
            caption_h = line_h if caption else 0
            labels_h = line_h * max(len(t.lines) for t in tiles)
            row_w = sum(self._slot_width(t) for t in tiles) + GAP * (len(tiles) - 1)
            row_h = caption_h + labels_h + max(t.image.shape[0] for t in tiles)
            layouts.append((height, caption_h, labels_h, row_w))
            width = max(width, row_w, text_size(caption, self.scale)[0])
            height += row_h + GAP
        width = max(width + 2 * MARGIN, self.min_width)
        canvas = np.empty((height + MARGIN - GAP, width, 3), dtype=np.float32)
        canvas[:] = BACKGROUND
        draw_text(canvas, MARGIN, MARGIN, self.title, 3, TEXT)
        if self.subtitle:
            draw_text(canvas, MARGIN, MARGIN + text_size("A", 3)[1] + LINE, self.subtitle, self.scale, DIM)
        for (caption, tiles), (top, caption_h, labels_h, row_w) in zip(self.rows, layouts):
            if caption:
                draw_text(canvas, MARGIN, top, caption, self.scale, TEXT)
            x = (width - row_w) // 2
            for tile in tiles:
                y = top + caption_h
                for k, line in enumerate(tile.lines):
                    draw_text(canvas, x, y, line, self.scale, TEXT if k == 0 else DIM)
                    y += line_h
                h, w = tile.image.shape[:2]
                canvas[top + caption_h + labels_h:top + caption_h + labels_h + h, x:x + w] = tile.image
                x += self._slot_width(tile) + GAP
        return canvas

    def write(self, path):
        """Writes the sheet as a 16-bit PNG; returns its (width, height)."""
        from penumbra import native  # the add-on is loaded in every demo Blender
        canvas = self.render()
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        native.require().image.write_png16(path, canvas, "sRGB")
        return canvas.shape[1], canvas.shape[0]
