// The live camera beside the key image the robot heads for. The stream is found through the
// MAVLink camera protocol by the ground station (the `camera` request) and relayed by it
// (/api/vehicles/SYS/camera.mjpg); the key image comes over MAVLink FTP like the memory's.
// The points of the key image matched with the newest frame (camera-matches.json, from the
// robot's /matches.json) are drawn over it in the colours of the camera's: green for the
// inliers of the estimate, orange for the other matches.

const $ = id => document.getElementById(id);
const RETRY_MS = 3000;
const INLIER = "rgb(60, 200, 60)", OTHER = "rgb(255, 140, 0)";
const POINT_RADIUS_PX = 3;

export class CameraView {
  constructor(app) {
    this.app = app;
    this.system = null;
    this.stream = null;
    this.target = null;
    this.retry = null;
    this.poll = null;
    this.fetching = false;
    $("camera-matches").onchange = () => this.show();
    $("camera-image").onerror = () => this.lost();
  }

  // A vehicle was selected: ask for its stream.
  async start(system, refresh = false) {
    clearTimeout(this.retry);
    clearInterval(this.poll);
    this.clearMatches();
    this.system = system;
    this.stream = null;
    this.target = null;
    $("camera-image").removeAttribute("src");
    $("target-image").removeAttribute("src");
    $("target-caption").textContent = "target key image: none yet";
    $("camera-caption").textContent = "camera: asking the vehicle…";
    const reply = await this.app.link.request("camera", { system, refresh });
    if (system !== this.system) return;  // another vehicle selected meanwhile
    if (!reply.ok) {
      $("camera-caption").textContent = `camera: ${reply.error}`;
      return;
    }
    this.stream = reply.camera;
    this.show();
  }

  show() {
    if (!this.stream) return;
    const s = this.stream;
    const matches = $("camera-matches").checked;
    $("camera-image").src = `${s.url}?${matches ? "matches=1&" : ""}t=${Date.now()}`;
    $("camera-caption").textContent = `camera '${s.name}': ${s.width}x${s.height}, `
      + `${s.rate_hz.toFixed(0)} frames/s at most${matches ? ", matched points drawn" : ""}`;
    clearInterval(this.poll);
    this.clearMatches();
    if (matches) this.poll = setInterval(() => this.fetchMatches(), Math.max(100, 1000 / s.rate_hz));
  }

  clearMatches() {
    const canvas = $("target-matches");
    canvas.getContext("2d").clearRect(0, 0, canvas.width, canvas.height);
    canvas.dataset.points = "0";
  }

  // The newest frame's matches, drawn on the key image when they are of that key image.
  async fetchMatches() {
    if (this.fetching || this.target === null || this.target < 0) return;
    const system = this.system, target = this.target;
    this.fetching = true;
    let m = null;
    try {
      const reply = await fetch(`/api/vehicles/${system}/camera-matches.json`);
      if (reply.ok) m = await reply.json();
    } catch (e) {
      m = null;  // the next poll tries again; the stream's own error says what is wrong
    } finally {
      this.fetching = false;
    }
    if (system !== this.system || target !== this.target) return;
    if (!m || m.key !== target || !Array.isArray(m.key_xy)) {
      this.clearMatches();
      return;
    }
    this.drawMatches(m);
  }

  drawMatches(m) {
    const image = $("target-image"), canvas = $("target-matches");
    if (!image.naturalWidth) return;
    canvas.width = image.clientWidth;
    canvas.height = image.clientHeight;
    // The image is shown contained (style.css): scaled to fit, centred.
    const scale = Math.min(canvas.width / image.naturalWidth, canvas.height / image.naturalHeight);
    const left = (canvas.width - image.naturalWidth * scale) / 2;
    const top = (canvas.height - image.naturalHeight * scale) / 2;
    const ctx = canvas.getContext("2d");
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.lineWidth = 1;
    m.key_xy.forEach(([x, y], k) => {
      ctx.strokeStyle = m.inliers && m.inliers[k] ? INLIER : OTHER;
      ctx.beginPath();
      ctx.arc(left + x * scale, top + y * scale, POINT_RADIUS_PX, 0, 2 * Math.PI);
      ctx.stroke();
    });
    canvas.dataset.points = String(m.key_xy.length);
    const inliers = m.inliers ? m.inliers.filter(Boolean).length : 0;
    $("target-caption").textContent = `target: ${this.app.memory.describe(m.key)}; `
      + `${m.key_xy.length} points matched with the camera's (${inliers} inliers)`;
  }

  lost() {
    if (!this.stream || !$("camera-image").getAttribute("src")) return;
    clearInterval(this.poll);
    this.clearMatches();
    $("camera-caption").textContent = "camera: the stream stopped; asking again…";
    clearTimeout(this.retry);
    const system = this.system;
    this.retry = setTimeout(() => { if (system === this.system) this.start(system, true); },
      RETRY_MS);
  }

  // The servo state's next key image (VISUAL_SERVO_STATUS next_key; negative: none).
  setTarget(next) {
    if (next === this.target || this.system === null) return;
    this.target = next;
    this.clearMatches();
    if (next === null || next < 0) {
      $("target-image").removeAttribute("src");
      $("target-caption").textContent = "target key image: none";
      return;
    }
    $("target-image").src = `/api/vehicles/${this.system}/memory/images/${next}.png`;
    $("target-caption").textContent = `target: ${this.app.memory.describe(next)}`;
  }
}
