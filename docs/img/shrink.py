"""The committed copies of the report's figures (docs/img/), from the ones `thermocontact
figures` or `reproduce` draws into docs/figures/ (ignored: full-colour PNGs of 0.1-1.5 MB).

    cargo run --release -- figures --out docs/figures && python3 docs/img/shrink.py

A 128-colour palette without dithering keeps the plots as drawn (the colour maps have fewer
steps than that) at 5-20 times fewer bytes, under the repository's 300 KB per figure. Needs
Pillow (`pip install pillow`).
"""
from pathlib import Path

from PIL import Image

HERE = Path(__file__).resolve().parent
FIGURES = ["fig2_deformed", "fig3_expansion", "slip_history", "contact_profiles"]

for name in FIGURES:
    drawn = Image.open(HERE.parent / "figures" / f"{name}.png").convert("RGB")
    palette = drawn.quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    target = HERE / f"{name}.png"
    palette.save(target, optimize=True)
    size = target.stat().st_size
    assert size < 300_000, f"{target}: {size} bytes, over the 300 KB a committed figure may have"
    print(f"{target.relative_to(HERE.parent.parent)}: {size // 1000} KB")
