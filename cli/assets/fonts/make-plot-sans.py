"""Rebuild PlotSans-{Regular,Bold}.ttf from Liberation Sans 2.1.5 (SIL OFL 1.1).

Subset to the characters the figures use (Latin, Greek, punctuation, super- and
subscripts, arrows, mathematical operators), hinting dropped (the renderer does not hint),
and renamed: the OFL reserves the name "Liberation" for unmodified fonts.

    pip install fonttools
    python make-plot-sans.py /usr/share/fonts/truetype/liberation2   # Debian: fonts-liberation2
"""
import sys
from fontTools import subset
from fontTools.ttLib import TTFont

UNICODES = ("U+0020-007E,U+00A0-017F,U+0370-03FF,U+1D40-1D6A,U+2000-206F,U+2070-209F,"
            "U+2190-21FF,U+2200-22FF,U+2300-23FF,U+25A0-25FF")
FAMILY = "Plot Sans"

for style in ("Regular", "Bold"):
    src = f"{sys.argv[1]}/LiberationSans-{style}.ttf"
    out = f"PlotSans-{style}.ttf"
    opts = subset.Options()
    opts.hinting = False
    opts.layout_features = ["kern", "liga"]
    opts.name_IDs = ["*"]
    font = TTFont(src)
    sub = subset.Subsetter(opts)
    sub.populate(unicodes=subset.parse_unicodes(UNICODES))
    sub.subset(font)
    names = {1: FAMILY, 3: f"{FAMILY} {style} (subset of Liberation Sans 2.1.5)",
             4: f"{FAMILY} {style}" if style != "Regular" else FAMILY,
             6: f"PlotSans-{style}", 16: FAMILY, 17: style}
    for rec in font["name"].names:
        if rec.nameID in names:
            rec.string = names[rec.nameID]
    for rec in list(font["name"].names):
        if rec.nameID == 2:
            rec.string = style
    font.save(out)
    print(out)
