"""The web view in headless Chromium against a real cornerpose_server replaying one
recorded frame (looped): the page must show as many boxes as a gRPC Detect on the
same frame finds. Saves the 2D and the turned 3D view as PNGs.

  run_view_test.py SERVER CLI FRAMES_DIR FRAME APP_DIR OUT_DIR

APP_DIR is the web build's npm tree (BUILD/web/app: playwright-core); OUT_DIR gets
view_2d.png and view_3d.png (docs/ holds committed copies)."""

import pathlib
import shutil
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from live_server import LiveServer, detect_count  # noqa: E402


def main():
    server, cli, frames, frame, app, out = sys.argv[1:7]
    app, out = pathlib.Path(app), pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    # The script resolves playwright-core from its own folder: run it from the npm tree.
    script = app / "view_test.mjs"
    shutil.copy(pathlib.Path(__file__).parent / "view_test.mjs", script)
    with LiveServer(server, pathlib.Path(frames), frame) as s:
        expected = detect_count(cli, s.address, "one", "carton_s", out / "detect.json")
        print(f"run_view_test: Detect on frame {frame} finds {expected} boxes")
        if expected == 0:
            sys.exit("run_view_test: the frame has no boxes to show; pick another")
        result = subprocess.run(["node", str(script), f"{s.url}/sources/one", str(expected),
                                 str(out / "view_2d.png"), str(out / "view_3d.png")],
                                timeout=300)
    for name in ("view_2d.png", "view_3d.png"):
        if not (out / name).is_file() or (out / name).stat().st_size < 1000:
            sys.exit(f"run_view_test: no screenshot {out / name}")
    sys.exit(result.returncode)


if __name__ == "__main__":
    main()
