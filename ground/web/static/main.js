// The page: the WebSocket to the ground station, the fleet view and the vehicle view.
// Plain ES modules, no build step; every asset is served by `vmnav ground web` itself.

import { CameraView } from "./camera.js";
import { loadLogs } from "./logs.js";
import { DEG, ScrollingPlot, TrailView } from "./plot.js";
import { MemoryBrowser } from "./memory.js";
import { showMessage } from "./message.js";
import { ParamsTable } from "./params.js";
import { Teleop } from "./teleop.js";

const $ = id => document.getElementById(id);
const fmt = (v, digits, unit = "") => (v === null || v === undefined ? "–" : v.toFixed(digits) + unit);
const signed = (v, digits, unit = "") => (v === null || v === undefined ? "–"
  : (v >= 0 ? "+" : "") + v.toFixed(digits) + unit);

// The WebSocket: requests with an id, replies matched to them; reconnects when lost.
class Link {
  constructor(onMessage) {
    this.onMessage = onMessage;
    this.nextId = 1;
    this.pending = new Map();
    this.open();
  }

  open() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    this.ws = new WebSocket(`${scheme}//${location.host}/ws`);
    this.ws.onopen = () => { $("connection").textContent = "connected"; $("connection").className = "good"; };
    this.ws.onclose = () => {
      $("connection").textContent = "disconnected, retrying…";
      $("connection").className = "bad";
      for (const [, resolve] of this.pending) resolve({ ok: false, error: "connection lost" });
      this.pending.clear();
      setTimeout(() => this.open(), 1000);
    };
    this.ws.onmessage = event => {
      const message = JSON.parse(event.data);
      if (message.type === "reply" && this.pending.has(message.id)) {
        this.pending.get(message.id)(message);
        this.pending.delete(message.id);
      }
      this.onMessage(message);
    };
  }

  get ready() { return this.ws.readyState === WebSocket.OPEN; }

  // Send {cmd, ...fields}; resolves with the reply (a refusal too: {ok: false, error}).
  request(cmd, fields = {}) {
    if (!this.ready) return Promise.resolve({ ok: false, error: "not connected" });
    const id = this.nextId++;
    this.ws.send(JSON.stringify({ id, cmd, ...fields }));
    return new Promise(resolve => this.pending.set(id, resolve));
  }

  // Fire and forget (the 10 Hz drive messages): only a refusal is shown.
  post(cmd, fields = {}) {
    if (this.ready) this.ws.send(JSON.stringify({ cmd, ...fields }));
  }
}

class App {
  constructor() {
    this.client = null;
    this.vehicles = new Map();
    this.selected = null;
    this.teleopOwner = null;
    this.now = 0;
    this.dirty = true;
    this.lastServo = null;
    this.lastOdom = null;
    this.plots = {
      matches: new ScrollingPlot($("plot-matches"), { digits: 0 }),
      y: new ScrollingPlot($("plot-y"), { digits: 3, color: "#6a1b9a" }),
      theta: new ScrollingPlot($("plot-theta"), { digits: 1, color: "#6a1b9a" }),
      err: new ScrollingPlot($("plot-err"), { digits: 1, color: "#c62828" }),
      v: new ScrollingPlot($("plot-v"), { digits: 2, color: "#2e7d32" }),
      omega: new ScrollingPlot($("plot-omega"), { digits: 1, color: "#2e7d32" }),
    };
    this.trail = new TrailView($("trail"));
    this.link = new Link(message => this.handle(message));
    this.memory = new MemoryBrowser(this);
    this.camera = new CameraView(this);
    this.params = new ParamsTable(this);
    this.teleop = new Teleop(this);
    this.wireControls();
    requestAnimationFrame(() => this.frame());
  }

  // A request about the selected vehicle; its outcome on the message line.
  async command(cmd, fields = {}) {
    const reply = await this.link.request(cmd, { system: this.selected ?? undefined, ...fields });
    if (!reply.ok) showMessage(reply.error, true);
    else if (reply.text) showMessage(reply.text);
    return reply;
  }

  wireControls() {
    $("arm").onclick = () => this.command("arm");
    $("hold").onclick = () => this.command("hold");
    $("estop").onclick = () => this.command("estop");
    $("mode-set").onclick = () => this.command("mode", { mode: $("mode-select").value });
    $("logs-load").onclick = () => loadLogs();
    loadLogs();
  }

  handle(message) {
    if (message.type === "hello") {
      this.client = message.client;
      for (const plot of Object.values(this.plots)) plot.clear();
      this.trail.clear();
      $("notice-list").replaceChildren();
      if (message.last) this.update(message.last, message.samples, message.notices);
    } else if (message.type === "update") {
      this.update(message, message.samples, message.notices);
    } else if (message.type === "reply" && !message.ok && message.id === null) {
      showMessage(message.error, true);  // a fire-and-forget request refused
    }
  }

  update(update, samples, notices) {
    this.now = update.t;
    this.teleopOwner = update.teleop_owner;
    this.vehicles = new Map(update.vehicles.map(v => [v.system_id, v]));
    if (this.selected === null && update.vehicles.length > 0) {
      this.select(update.vehicles[0].system_id);
    }
    const key = String(this.selected);
    for (const sample of samples[key] ?? []) this.addSample(sample);
    for (const text of notices[key] ?? []) {
      const item = document.createElement("li");
      item.textContent = text;
      $("notice-list").append(item);
    }
    this.renderFleet();
    this.renderVehicle();
    this.teleop.render();
    this.dirty = true;
  }

  addSample(s) {
    if (s.kind === "odom") {
      this.lastOdom = s;
      this.plots.v.push(s.t, s.v);
      this.plots.omega.push(s.t, s.omega === null ? null : s.omega * DEG);
      this.trail.push(s.x, s.y, s.yaw);
    } else if (s.kind === "servo") {
      this.lastServo = s;
      const following = s.next >= 0;
      this.plots.matches.push(s.t, following ? s.matches : null);
      this.plots.y.push(s.t, s.y);
      this.plots.theta.push(s.t, s.theta === null ? null : s.theta * DEG);
      this.plots.err.push(s.t, s.err_max);
      this.memory.highlight(s.next, s.goal);
      this.camera.setTarget(s.next);
      if (s.state === "teaching") this.memory.teaching(s.current);
    }
  }

  select(system) {
    if (system === this.selected) return;
    this.selected = system;
    for (const plot of Object.values(this.plots)) plot.clear();
    this.trail.clear();
    this.lastServo = this.lastOdom = null;
    $("notice-list").replaceChildren();
    $("vehicle").hidden = false;
    this.command("select");
    this.memory.load(false);
    this.camera.start(system);
    this.renderFleet();
  }

  // Rows are kept per vehicle and their cells rewritten: no flicker, and a row clicked
  // stays the same element.
  renderFleet() {
    const body = $("fleet-rows");
    if (this.vehicles.size) body.querySelector(".empty")?.remove();
    for (const v of this.vehicles.values()) {
      let row = body.querySelector(`tr[data-system="${v.system_id}"]`);
      if (!row) {
        row = document.createElement("tr");
        row.dataset.system = v.system_id;
        for (let i = 0; i < 9; i++) row.append(document.createElement("td"));
        row.onclick = () => this.select(v.system_id);
        body.append(row);
      }
      row.classList.toggle("selected", v.system_id === this.selected);
      const link = v.link_received === null ? "–" : `${Math.round(v.link_received * 100)} %`;
      const mission = v.mission ? `${v.mission.seq}/${v.mission.total} ${v.mission.state}` : "–";
      const cells = [v.system_id, v.name, v.mode, v.armed ? "armed" : "disarmed",
        fmt(v.battery_v, 1, " V"), `${link}, ${v.heartbeat_age_s.toFixed(1)} s`, mission,
        v.servo_state ?? "–", v.failsafes.join(", ") || "none"];
      cells.forEach((text, i) => {
        if (row.cells[i].textContent !== String(text)) row.cells[i].textContent = text;
      });
      row.cells[8].className = v.failsafes.length ? "failsafe" : "";
    }
  }

  renderVehicle() {
    const v = this.vehicles.get(this.selected);
    if (!v) return;
    $("v-system").textContent = `${v.system_id} (${v.name})`;
    $("v-mode").textContent = v.mode;
    $("v-armed").textContent = v.armed ? "armed" : "disarmed";
    $("v-state").textContent = v.servo_state ?? v.status;
    const s = this.lastServo, o = this.lastOdom;
    const parts = [];
    if (s) {
      parts.push(this.memory.progressText(s.current, s.next, s.goal));
      parts.push(`${s.matches} matches`, `y ${signed(s.y, 3, " m")}`,
        `θ ${signed(s.theta === null ? null : s.theta * DEG, 1, "°")}`,
        `errImageMax ${fmt(s.err_max, 1, " px")}`);
    }
    if (o) {
      parts.push(`v ${signed(o.v, 2, " m/s")}`,
        `ω ${signed(o.omega === null ? null : o.omega * DEG, 1, " °/s")}`);
    }
    $("servo-summary").textContent = parts.join(" · ") || "no servo state yet";
  }

  frame() {
    if (this.dirty) {
      for (const plot of Object.values(this.plots)) plot.draw(this.now);
      this.trail.draw();
      this.dirty = false;
    }
    requestAnimationFrame(() => this.frame());
  }
}

window.vmnav = new App();
