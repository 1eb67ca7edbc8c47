// The live camera beside the key image the robot heads for. The stream is found through the
// MAVLink camera protocol by the ground station (the `camera` request) and relayed by it
// (/api/vehicles/SYS/camera.mjpg); the key image comes over MAVLink FTP like the memory's.

const $ = id => document.getElementById(id);
const RETRY_MS = 3000;

export class CameraView {
  constructor(app) {
    this.app = app;
    this.system = null;
    this.stream = null;
    this.target = null;
    this.retry = null;
    $("camera-matches").onchange = () => this.show();
    $("camera-image").onerror = () => this.lost();
  }

  // A vehicle was selected: ask for its stream.
  async start(system, refresh = false) {
    clearTimeout(this.retry);
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
  }

  lost() {
    if (!this.stream || !$("camera-image").getAttribute("src")) return;
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
    if (next === null || next < 0) {
      $("target-image").removeAttribute("src");
      $("target-caption").textContent = "target key image: none";
      return;
    }
    $("target-image").src = `/api/vehicles/${this.system}/memory/images/${next}.png`;
    $("target-caption").textContent = `target: ${this.app.memory.describe(next)}`;
  }
}
