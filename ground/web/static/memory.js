// The memory browser: the robot's visual paths as a graph and as strips of key-image
// thumbnails (fetched over MAVLink FTP by the ground station, cached there); click one to
// see it large with the route the robot would take to it, and send it as the goal, or add
// it to a mission of several goals.

import { MemoryGraph } from "./graph.js";
import { showMessage } from "./message.js";

const $ = id => document.getElementById(id);

export class MemoryBrowser {
  constructor(app) {
    this.app = app;
    this.index = null;  // {paths: [{id, name, keyframe_ids}], keyframes: {id: {...}}}
    this.largeKey = null;
    this.largeUrl = null;
    this.mission = [];
    this.taught = null;  // the last key image of the path being taught shown; null: none
    this.graph = new MemoryGraph($("memory-graph"), key => this.showLarge(key));
    $("memory-refresh").onclick = () => this.load(true);
    $("large-go").onclick = () => this.goto(this.largeKey);
    $("large-add").onclick = () => this.addGoal(this.largeKey);
    $("mission-start").onclick = () => this.startMission();
    $("mission-clear").onclick = () => { this.mission = []; this.renderMission(); };
    $("goal-form").onsubmit = event => {
      event.preventDefault();
      this.goto(Number($("goal-key").value));
    };
    $("goal-photo-go").onclick = () => this.gotoPhoto($("goal-photo").files[0]);
  }

  // Upload a photo; the robot finds it in its memory (or says why not) and goes there.
  async gotoPhoto(file) {
    if (!file) { showMessage("choose a photo first", true); return; }
    showMessage(`${file.name}: looking it up in the robot's memory...`);
    const response = await fetch(`/api/vehicles/${this.app.selected}/goto-photo`,
                                 { method: "POST", body: file });
    const body = await response.json().catch(() => ({ error: response.statusText }));
    if (!response.ok) { showMessage(`${file.name}: ${body.error}`, true); return; }
    showMessage(`${file.name}: found at key image ${body.keyframe_id}; going there`);
    this.highlight(body.keyframe_id, body.keyframe_id);
  }

  url(kind, key) {
    return `/api/vehicles/${this.app.selected}/memory/${kind}/${key}.png`;
  }

  async load(refresh) {
    const reply = await this.app.command("memory", { refresh });
    if (!reply.ok) return;
    this.index = reply.memory;
    const strips = this.index.paths.map(path => {
      const block = document.createElement("div");
      const title = document.createElement("h4");
      title.textContent = `path ${path.id} '${path.name}': ${path.keyframe_ids.length} key images`;
      const strip = document.createElement("div");
      strip.className = "strip";
      for (const key of path.keyframe_ids) {
        const img = document.createElement("img");
        img.loading = "lazy";
        img.alt = img.title = `key image ${key}`;
        img.dataset.key = key;
        img.onerror = () => { img.classList.add("broken"); img.title = `key image ${key}: not fetched`; };
        img.onclick = () => this.showLarge(key);
        img.src = this.url("thumbnails", key);
        strip.append(img);
      }
      block.append(title, strip);
      return block;
    });
    if (strips.length === 0) strips.push(document.createTextNode("the memory is empty"));
    $("memory-paths").replaceChildren(...strips);
    this.taught = null;
    $("teach-strip").replaceChildren();
    this.graph.setIndex(this.index);
  }

  async showLarge(key) {
    const response = await fetch(this.url("images", key));
    if (!response.ok) {
      const body = await response.json().catch(() => ({ error: response.statusText }));
      showMessage(`key image ${key}: ${body.error}`, true);
      return;
    }
    if (this.largeUrl) URL.revokeObjectURL(this.largeUrl);
    this.largeUrl = URL.createObjectURL(await response.blob());
    this.largeKey = key;
    $("large-image").src = this.largeUrl;
    $("large-caption").textContent = this.describe(key);
    $("large-route").textContent = "route: planning…";
    $("memory-large").hidden = false;
    this.graph.mark({ chosen: key });
    this.showRoute(key);
  }

  // The key images the robot would pass to get to `key` from where it last said it was.
  async showRoute(key) {
    const reply = await this.app.link.request("route", { system: this.app.selected, key });
    if (key !== this.largeKey) return;  // another key image chosen meanwhile
    const route = reply.ok ? reply.route : [];
    $("large-route").textContent = !reply.ok ? `route: ${reply.error}`
      : route.length ? `route: ${route.join(" → ")}  (${reply.text})` : `route: ${reply.text}`;
    this.graph.mark({ route });
    for (const img of document.querySelectorAll(".strip img")) {
      img.classList.toggle("route", route.includes(Number(img.dataset.key)));
    }
  }

  goto(key) {
    return this.app.command("goto", { key });
  }

  addGoal(key) {
    if (key === null) return;
    this.mission.push(key);
    this.renderMission();
  }

  renderMission() {
    $("mission-goals").textContent = this.mission.length
      ? this.mission.join(" → ") : "none (add key images with “Add to mission”)";
    $("mission-start").disabled = this.mission.length === 0;
  }

  async startMission() {
    const reply = await this.app.command("mission", { keys: this.mission });
    if (reply.ok) { this.mission = []; this.renderMission(); }
  }

  describe(key) {
    const info = this.index?.keyframes[String(key)];
    if (!info) return `key image ${key}`;
    const path = this.index.paths.find(p => p.id === info.path_id);
    return `key image ${key}: ${info.index + 1} of ${path ? path.keyframe_ids.length : "?"} `
      + `on path '${path ? path.name : info.path_id}', ${info.distance_m.toFixed(2)} m from its start`;
  }

  // "key image i of n on 'name'" for the key image being servoed to.
  progressText(current, next, goal) {
    const info = this.index?.keyframes[String(next)];
    const path = info && this.index.paths.find(p => p.id === info.path_id);
    const where = path ? `key image ${info.index + 1} of ${path.keyframe_ids.length} on '${path.name}'`
      : "no key image";
    return `${where} (key ${current} → ${next}, goal ${goal})`;
  }

  // While teaching, VISUAL_SERVO_STATUS current_key is the last key image taken (the id it
  // gets when stored): show every one up to it, fetched from the robot's /teaching/.
  teaching(current) {
    if (current < 0 || current === this.taught) return;
    const known = Object.keys(this.index?.keyframes ?? {}).map(Number);
    let key = this.taught === null ? (known.length ? Math.max(...known) + 1 : current)
      : this.taught + 1;
    if (this.taught !== null && current < this.taught) {  // another path: start again
      $("teach-strip").replaceChildren();
      key = current;
    }
    for (; key <= current; key++) {
      const img = document.createElement("img");
      img.alt = img.title = `key image ${key} (being taught)`;
      img.dataset.key = key;
      img.onerror = () => { img.classList.add("broken"); };
      img.src = `/api/vehicles/${this.app.selected}/teaching/${key}.png`;
      $("teach-strip").append(img);
    }
    this.taught = current;
    $("teach-count").textContent = `${$("teach-strip").children.length} key images taken`;
  }

  highlight(next, goal) {
    if (next !== this.graph.next || goal !== this.graph.goal) this.graph.mark({ next, goal });
    for (const img of document.querySelectorAll(".strip img")) {
      const key = Number(img.dataset.key);
      img.classList.toggle("next", key === next);
      img.classList.toggle("goal", key === goal);
    }
  }
}
