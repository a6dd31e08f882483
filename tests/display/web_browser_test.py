#!/usr/bin/env python3
"""The operator console in a real headless browser (issue 31): Debian's Chromium driven by
Selenium against `rtwall run --web` (headless, local clients, orbiting).

  web_browser_test.py RTWALL SCRATCH_DIR

It opens the printed URL (the token's cookie), sees the thumbnail change as the camera orbits,
sets the camera from the page (the orbit stops), hides a part by its checkbox and sees the wall's
frame change, adds a section plane by the form, saves the session, changes the view, restores the
session through the page's file input and gets the same frame bit for bit; and `rtwall run
--session` renders that same frame; on a wall of two display nodes the thumbnail (from the
nodes) appears and follows the orbit and the screenshot is the wall's. Bounded: every wait has a timeout, the run is killed at the end.
"""
import json
import os
import re
import struct
import subprocess
import sys
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.common.exceptions import StaleElementReferenceException
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys

RTWALL, SCRATCH = sys.argv[1], sys.argv[2]
os.makedirs(SCRATCH, exist_ok=True)
CONFIG = os.path.join(SCRATCH, "run.toml")
with open(CONFIG, "w") as f:
    f.write('scene = "builtin:knots"\n[image]\nwidth = 240\nheight = 180\n[cluster]\nclients = 1\nasync = false\n'
            '[run]\nframes = 0\nwrite_every = 0\norbit = 2.0\n')


def fail(what):
    print("web_browser_test: " + what, file=sys.stderr)
    sys.exit(1)


def wait_for(what, check, seconds=60):
    end = time.time() + seconds
    while time.time() < end:
        value = check()
        if value:
            return value
        time.sleep(0.1)
    fail("timed out waiting for " + what)


def start_console(*extra):
    """`rtwall run CONFIG --headless --web` with `extra` arguments; the process and its printed URL."""
    run = subprocess.Popen([RTWALL, "run", CONFIG, "--headless", "--web", "127.0.0.1:0", *extra],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    end = time.time() + 120
    while time.time() < end:
        line = run.stdout.readline()
        if not line:
            fail("rtwall run %s ended before the console started" % " ".join(extra))
        m = re.match(r"web console: (\S+)", line)
        if m:
            return run, m.group(1)
    fail("no 'web console:' line from rtwall run " + " ".join(extra))


def open_browser(url, downloads=None):
    """Headless Chromium on the printed URL (its cookie, then the page)."""
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,1000"):
        options.add_argument(a)
    if downloads:
        options.add_experimental_option("prefs", {"download.default_directory": downloads})
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    driver.set_page_load_timeout(60)
    driver.get(url)
    if "rtwall console" not in driver.title:
        fail("the page did not load: " + driver.title)
    return driver


def thumbnail_follows_orbit(driver, where):
    """The page's thumbnail appears, a newer one comes and its image changes; the element."""
    thumb = driver.find_element(By.ID, "thumbnail")
    first = wait_for("a thumbnail" + where, lambda: thumb.get_attribute("data-frame"))
    wait_for("a newer thumbnail" + where, lambda: (thumb.get_attribute("data-frame") or first) != first)
    src_a = thumb.get_attribute("src")
    wait_for("the thumbnail's image to change" + where, lambda: thumb.get_attribute("src") != src_a)
    return thumb


def page_said_nothing(driver, where):
    errors = driver.find_element(By.ID, "error").text
    if errors:
        fail("the page" + where + " said: " + errors)


def stop(run, driver):
    if driver:
        driver.quit()
    run.terminate()
    try:
        run.wait(timeout=30)
    except subprocess.TimeoutExpired:
        run.kill()


run, url = start_console("--out", os.path.join(SCRATCH, "frames"))
driver = None
try:
    base, token = url.split("/?token=")

    def call(method, path, body=None, raw=False):
        data = None if body is None else (body if isinstance(body, bytes) else json.dumps(body).encode())
        req = urllib.request.Request(base + path, data=data, method=method, headers={"Authorization": "Bearer " + token})
        with urllib.request.urlopen(req, timeout=30) as r:
            payload = r.read()
        return payload if raw else json.loads(payload)

    def settle():
        start = call("GET", "/api/status")["steps"]
        wait_for("three more frames", lambda: call("GET", "/api/status")["steps"] >= start + 3)

    driver = open_browser(url, SCRATCH)

    # The thumbnail follows the orbit.
    thumb = thumbnail_follows_orbit(driver, "")

    # The camera from the page: the orbit stops.
    for field, value in (("camera-position", "0.5, 2.5, 9"), ("camera-target", "0, 0, 0"), ("camera-up", "0, 1, 0")):
        # As an operator does: into the field, everything selected, typed over. (WebDriver's
        # clear() takes the focus away again, and the field follows the camera until typed in.)
        box = driver.find_element(By.ID, field)
        box.click()
        box.send_keys(Keys.CONTROL, "a")
        box.send_keys(value)
    typed = [driver.find_element(By.ID, f).get_attribute("value") for f in ("camera-position", "camera-target", "camera-up")]
    driver.find_element(By.CSS_SELECTOR, "#camera-form button").click()
    if typed != ["0.5, 2.5, 9", "0, 0, 0", "0, 1, 0"]:
        fail("the camera fields hold " + repr(typed) + ", not what was typed")
    wait_for("the camera", lambda: abs(call("GET", "/api/camera")["position"][2] - 9) < 1e-5 and not call("GET", "/api/status")["flying"])
    settle()
    before = call("GET", "/api/screenshot.png", raw=True)
    settle()
    if call("GET", "/api/screenshot.png", raw=True) != before:
        fail("the frame still changes after the camera was set (the orbit did not stop)")

    # Hide a knot by its checkbox (the floor stays: the measurement below clicks on it).
    parts = call("GET", "/api/parts")["parts"]
    knot = [p for p in parts if p["path"] == "knot0"]
    if not knot:
        fail("the scene lists no part 'knot0': %s" % [p["path"] for p in parts])
    part = knot[0]["id"]
    box = wait_for("the part list", lambda: driver.find_elements(By.CSS_SELECTOR, "#parts li[data-id='%d'] input[type=checkbox]" % part))[0]
    box.click()
    wait_for("the part hidden", lambda: not call("GET", "/api/parts")["parts"][part]["visible"])
    settle()
    hidden = call("GET", "/api/screenshot.png", raw=True)
    if hidden == before:
        fail("hiding part 'knot0' did not change the frame")

    # A section plane by the form.
    driver.find_element(By.ID, "section-normal").clear()
    driver.find_element(By.ID, "section-normal").send_keys("1, 0, 0")
    driver.find_element(By.ID, "section-offset").clear()
    driver.find_element(By.ID, "section-offset").send_keys("0.2")
    driver.find_element(By.CSS_SELECTOR, "#section-form button").click()
    wait_for("the section plane", lambda: len(call("GET", "/api/sections")["sections"]) == 1)
    wait_for("the plane in the page's list", lambda: driver.find_elements(By.CSS_SELECTOR, "#sections li"))
    settle()
    cut = call("GET", "/api/screenshot.png", raw=True)
    if cut == hidden:
        fail("the section plane did not change the frame")

    # A measurement by two clicks on the thumbnail (right of the cut, low on the floor).
    from selenium.webdriver.common.action_chains import ActionChains
    driver.find_element(By.ID, "measure-toggle").click()
    size = thumb.size
    for fx, fy in ((0.25, 0.4), (0.3, 0.25)):
        ActionChains(driver).move_to_element_with_offset(thumb, int(size["width"] * fx), int(size["height"] * fy)).click().perform()
    def measurement_listed():
        said = driver.find_element(By.ID, "error").text
        if said:
            fail("the page said: " + said)
        try:  # the list is drawn anew on every state event: an item may go stale under our hands
            items = driver.find_elements(By.CSS_SELECTOR, "#measurements li")
            return items[0].text if items else None
        except StaleElementReferenceException:
            return None
    listed = wait_for("the measurement", measurement_listed)
    m = call("GET", "/api/measurements")["measurements"]
    if len(m) != 1 or not m[0]["distance"] > 0:
        fail("the measurement by two clicks: %s" % m)
    if "units" not in listed:
        fail("the page lists the measurement as: " + listed)

    # Save the session, change the view, restore it through the page: the same frame.
    session = call("GET", "/api/session", raw=True)
    session_file = os.path.join(SCRATCH, "session.toml")
    with open(session_file, "wb") as f:
        f.write(session)
    driver.find_element(By.ID, "show-all").click()
    wait_for("all parts shown", lambda: call("GET", "/api/parts")["parts"][part]["visible"])
    call("POST", "/api/camera", {"position": [3, 1, 6], "target": [0, 0, 0]})
    settle()
    if call("GET", "/api/screenshot.png", raw=True) == cut:
        fail("the view did not change before the restore")
    driver.find_element(By.ID, "session-file").send_keys(session_file)
    wait_for("the session restored", lambda: not call("GET", "/api/parts")["parts"][part]["visible"])
    settle()
    if call("GET", "/api/screenshot.png", raw=True) != cut:
        fail("the restored session's frame differs from the saved one")
    page_said_nothing(driver, "")
finally:
    stop(run, driver)

# A wall on two display nodes (local `rtwall display` processes): the pictures come from the
# nodes; the page's thumbnail appears and follows the orbit, and the screenshot is the wall's.
WALL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "configs", "wall", "two-nodes-2x2.toml")
run, url = start_console("--wall", WALL, "--out", os.path.join(SCRATCH, "nodes"))
driver = None
try:
    base, token = url.split("/?token=")
    driver = open_browser(url)
    thumbnail_follows_orbit(driver, " on display nodes")
    if driver.execute_script("return document.getElementById('thumbnail').naturalWidth") != 480:
        fail("the nodes' thumbnail is not 480 pixels wide")
    req = urllib.request.Request(base + "/api/screenshot.png", headers={"Authorization": "Bearer " + token})
    with urllib.request.urlopen(req, timeout=60) as r:
        png = r.read()
    if png[:8] != b"\x89PNG\r\n\x1a\n" or struct.unpack(">II", png[16:24]) != (648, 488):
        fail("the screenshot of the wall on display nodes is not a 648x488 PNG")
    page_said_nothing(driver, " on display nodes")
finally:
    stop(run, driver)

# rtwall run --session: its first frame is the saved one.
frames = os.path.join(SCRATCH, "again")
subprocess.run([RTWALL, "run", CONFIG, "--headless", "--frames", "1", "--write-every", "1", "--session", session_file, "--out", frames],
               check=True, timeout=120, stdout=subprocess.DEVNULL)
with open(os.path.join(frames, "frame_000001.png"), "rb") as f:
    if f.read() != cut:
        fail("rtwall run --session rendered another frame than the one saved")
print("web_browser_test: ok")
