// Teaching and driving from the page: start/stop a named path, and drive with the keyboard
// or a gamepad (the Gamepad API). While a key or the stick is held the page sends the axes
// 10 times a second; the ground station sends MANUAL_CONTROL at 10 Hz with them, and zeros
// once they are not refreshed (its dead-man). Releasing, leaving the page or closing it
// stops the robot.

const $ = id => document.getElementById(id);
const PERIOD_MS = 100;
const KEY_AXIS = 0.6;  // forward or turn for a held key, of the full range -1..1
const DEAD_ZONE = 0.15;
const KEYS = {
  w: [1, 0], arrowup: [1, 0], s: [-1, 0], arrowdown: [-1, 0],
  a: [0, -1], arrowleft: [0, -1], d: [0, 1], arrowright: [0, 1],
};

export class Teleop {
  constructor(app) {
    this.app = app;
    this.held = new Set();
    this.moving = false;
    this.pending = false;
    $("teach-start").onclick = () => app.command("teach_start", { name: $("teach-name").value });
    $("teach-stop").onclick = async () => {
      const reply = await app.command("teach_stop");
      if (reply.ok) app.memory.load(true);  // the new path's key images
    };
    $("teleop").onchange = () => this.toggle($("teleop").checked);
    window.addEventListener("keydown", event => this.key(event, true));
    window.addEventListener("keyup", event => this.key(event, false));
    window.addEventListener("blur", () => this.held.clear());
    document.addEventListener("visibilitychange", () => this.held.clear());
    setInterval(() => this.tick(), PERIOD_MS);
  }

  get driving() { return $("teleop").checked && this.app.teleopOwner === this.app.client; }

  async toggle(on) {
    this.pending = true;
    this.held.clear();
    const reply = await this.app.command("teleop", { on });
    this.pending = false;
    // Updates sent before the reply still name the old driver; the reply is the news.
    if (reply.ok) this.app.teleopOwner = on ? this.app.client : null;
    else $("teleop").checked = false;
    this.render();
  }

  key(event, down) {
    const name = event.key.toLowerCase();
    if (!(name in KEYS) || !$("teleop").checked) return;
    if (event.target instanceof HTMLInputElement && event.target.type !== "checkbox") return;
    event.preventDefault();
    if (down) this.held.add(name); else this.held.delete(name);
  }

  // The axes now: the gamepad's left stick if it is off centre, else the keys.
  axes() {
    for (const pad of navigator.getGamepads ? navigator.getGamepads() : []) {
      if (!pad) continue;
      const x = -(pad.axes[1] ?? 0), r = pad.axes[0] ?? 0;
      if (Math.abs(x) > DEAD_ZONE || Math.abs(r) > DEAD_ZONE) {
        return [Math.abs(x) > DEAD_ZONE ? x : 0, Math.abs(r) > DEAD_ZONE ? r : 0];
      }
    }
    let x = 0, r = 0;
    for (const name of this.held) { x += KEYS[name][0] * KEY_AXIS; r += KEYS[name][1] * KEY_AXIS; }
    return [Math.max(-1, Math.min(1, x)), Math.max(-1, Math.min(1, r))];
  }

  tick() {
    if (!this.driving) return;
    const [x, r] = this.axes();
    const moving = x !== 0 || r !== 0;
    if (moving || this.moving) this.app.link.post("drive", { system: this.app.selected, x, r });
    this.moving = moving;
    $("drive-state").textContent = `driving: forward ${x.toFixed(2)}, turn ${r.toFixed(2)}`;
  }

  render() {
    if (!this.pending && $("teleop").checked && this.app.teleopOwner !== this.app.client) {
      $("teleop").checked = false;  // stopped by the station: hold, emergency stop, another page
    }
    if (!this.driving && !this.pending) $("drive-state").textContent = "not driving";
  }
}
