# Composes docs/images/ssaa-sponza-smaa.png (docs/adaptive-ssaa.md) from the pictures that
#   ssaa-gpu --quick --images DIR   (cargo bench -p deferred-adaptive-ssaa --bench ssaa-gpu -- …)
# writes: python3 docs/images/ssaa-smaa-row.py DIR docs/images/ssaa-sponza-smaa.png 384,300,640,492
# (needs Pillow). The crop x0,y0,x1,y1 is of the 1024×768 pictures, shown at twice the size.
import sys
from PIL import Image, ImageDraw
src, out = sys.argv[1], sys.argv[2]
box = tuple(int(v) for v in sys.argv[3].split(","))  # x0,y0,x1,y1
scale = 2
names = [("one-sample", "one sample"), ("smaa", "SMAA 1x"), ("adaptive", "adaptive"), ("full", "full SSAA 4x4")]
errors = [("error-one-sample", "error x4: one sample"), ("error-smaa", "error x4: SMAA 1x"), ("error-adaptive", "error x4: adaptive"), ("samples", "samples per pixel (adaptive)")]
w, h = (box[2] - box[0]) * scale, (box[3] - box[1]) * scale
pad = 18
canvas = Image.new("RGB", (4 * w + 3 * 4, 2 * (h + pad) + 4), "white")
draw = ImageDraw.Draw(canvas)
for row, items in enumerate([names, errors]):
    for col, (f, label) in enumerate(items):
        x, y = col * (w + 4), row * (h + pad + 4)
        if f:
            im = Image.open(f"{src}/ssaa-sponza-{f}.png").convert("RGB").crop(box).resize((w, h), Image.NEAREST)
            canvas.paste(im, (x, y + pad))
        draw.text((x + 4, y + 3), label, fill="black")
canvas.save(out, optimize=True)
