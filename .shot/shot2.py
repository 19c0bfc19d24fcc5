import sys, json
sys.path.insert(0, "/work/wt-val")
from playwright.sync_api import sync_playwright
html, png, anchor = sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else ""
with sync_playwright() as p:
    b = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
    page = b.new_page(viewport={"width": 1400, "height": 1100})
    page.goto("file://" + html + anchor)
    page.screenshot(path=png)
    b.close()
