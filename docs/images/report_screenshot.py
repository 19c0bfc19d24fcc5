"""docs/images/report.png: the report's header and summary, one image cross-check opened,
and the approximations map (three screenshots of the real page, stacked).

    python docs/images/report_screenshot.py report/index.html docs/images/report.png
"""
import io
import sys
from pathlib import Path

from PIL import Image
from playwright.sync_api import sync_playwright

html, out = sys.argv[1], sys.argv[2]
shots = []
with sync_playwright() as p:
    b = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
    page = b.new_page(viewport={"width": 1400, "height": 1000})
    page.goto(Path(html).resolve().as_uri())
    shots.append(page.screenshot(clip={"x": 0, "y": 0, "width": 1400, "height": 520}))
    row = page.locator('tr[id="renderer/mitsuba/sphere-on-floor"]')
    details = row.locator("xpath=following-sibling::tr[1]//details").first
    details.evaluate("d => d.open = true")
    box_a, box_b = row.bounding_box(), details.bounding_box()
    page.mouse.wheel(0, 0)
    shots.append(page.screenshot(full_page=True, clip={"x": 0, "y": box_a["y"], "width": 1400,
                                                      "height": min(box_b["y"] + box_b["height"] - box_a["y"], 760)}))
    fig = page.locator('h3[id="films/approximations/snake"] ~ figure').first
    box = page.locator('h2[id="approximations"]').bounding_box()
    fbox = fig.bounding_box()
    shots.append(page.screenshot(full_page=True, clip={"x": 0, "y": box["y"] - 10, "width": 1400,
                                                      "height": fbox["y"] + fbox["height"] - box["y"] + 40}))
    b.close()
images = [Image.open(io.BytesIO(s)).convert("RGB") for s in shots]
canvas = Image.new("RGB", (1400, sum(i.height for i in images) + 16 * (len(images) - 1)), (120, 120, 120))
y = 0
for i in images:
    canvas.paste(i, (0, y))
    y += i.height + 16
canvas.save(out, optimize=True)
print(canvas.size)
