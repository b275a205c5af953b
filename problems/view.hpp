#pragma once
// `liedyn view RUN_DIR`: RUN_DIR/view.html, one self-contained page that animates a run —
// bodies as their shapes, rods as tubes of their radius (edge frames on a toggle), the
// colliders; play/pause, a frame slider, speed, time, an orbit camera and the frame's energy,
// iterations and penetration from frames.csv. Nothing is fetched at view time: three.js
// (r111, Debian's libjs-three) and its OrbitControls are inlined, the run's poses packed as
// one base64 Float32Array (not as JSON per node: a 2000-frame rod of 160 edges stays a few
// MB), the shapes as JSON (problems/shapes.hpp). The page (problems/viewer/view_template.html,
// compiled in) reports what it loaded in its title and on the console:
//   "liedyn view: F frames, O objects" / "liedyn-view: loaded F frames, O objects".
// Its first view frames the whole run: every body (its solid, offset included) and rod node
// over all frames, and the colliders of finite size (not planes).
//
// Opened at a chosen frame and camera, for pictures and links: options in the URL fragment,
// joined by "&", e.g. view.html#frame=last&paused&hide=panel,ui
//   frame=K | frame=last  simulation frame K (as on the clock; an unwritten one: the nearest)
//   t=T                   the written frame nearest to time T s (frame wins over t)
//   paused, edges         no playing; rod edge frames on (a bare name or =1 on, =0 off)
//   hide=panel,ui,title   without the series panel, the control bar, the title line
//   camera=AZ,EL          azimuth about +z from +x, elevation (|EL| <= 89), degrees; default -60,23
//   fit=run | fit=frame   the camera fits the whole run (default), or the shown frame's bodies
//                         and rods only
//   zoom=Z                Z times closer than the fit
// A bad or unknown option is ignored with a console warning ("liedyn-view: warning: ..."), never
// an error page. Once the chosen frame is drawn the page logs "liedyn-view: drawn frame K
// (t = T s)", the cue for a screenshot (scripts/viewer/check_view.sh, scripts/gallery.sh);
// editing the fragment of an open page applies it again.
//
// It reads RUN_DIR/shapes.json, trajectory.csv and frames.csv (as `liedyn simulate` writes
// them, with --every or not), checks that they describe one run — every frame's rows the
// objects of shapes.json in order — and adds view.html to the folder as a unit of its own
// (problems/output_folder.hpp). Bad or missing files are a SceneError naming the file, the
// line or field, and the reason.

#include <cstdint>
#include <filesystem>

namespace liedyn {

struct ViewOptions {
  // Where three.min.js and examples/js/controls/OrbitControls.js are (libjs-three).
  std::filesystem::path three_dir = "/usr/share/javascript/three";
};

struct ViewSummary {
  int frames = 0;   // written frames (trajectory.csv's)
  int objects = 0;  // bodies + rods + colliders
  std::uintmax_t bytes = 0;  // of view.html
};

ViewSummary write_view(const std::filesystem::path& run_dir, const ViewOptions& options = {});

}  // namespace liedyn
