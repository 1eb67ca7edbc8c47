// The memory as a graph: one row per visual path, its key images as dots along it at their
// teach distance (paths run left to right, the way they were taught), the junctions as
// dashed lines between rows, and the planned route drawn over it. Rows are not a map: each
// path has its own odometry frame, so only distances along a path are to scale.

const ROW_PX = 34, LEFT_PX = 120, RIGHT_PX = 16, TOP_PX = 18, DOT_PX = 5;

export class MemoryGraph {
  constructor(canvas, onPick) {
    this.canvas = canvas;
    this.index = null;
    this.spots = new Map();  // key image id -> [x, y] px
    this.route = [];
    this.next = null;
    this.goal = null;
    this.chosen = null;
    canvas.onclick = event => {
      const key = this.keyAt(event.offsetX, event.offsetY);
      if (key !== null) onPick(key);
    };
  }

  setIndex(index) {
    this.index = index;
    this.route = [];
    this.layout();
    this.draw();
  }

  // The page's marks: the route planned, the key image servoed to, the goal, the one shown.
  mark({ route = this.route, next = this.next, goal = this.goal, chosen = this.chosen }) {
    Object.assign(this, { route, next, goal, chosen });
    this.draw();
  }

  layout() {
    this.spots.clear();
    const paths = this.index?.paths ?? [];
    this.canvas.height = TOP_PX + Math.max(1, paths.length) * ROW_PX;
    const longest = Math.max(1e-6, ...paths.map(p => this.lengthOf(p)));
    const scale = (this.canvas.width - LEFT_PX - RIGHT_PX) / longest;
    paths.forEach((path, row) => {
      for (const key of path.keyframe_ids) {
        const info = this.index.keyframes[String(key)];
        this.spots.set(key, [LEFT_PX + info.distance_m * scale, TOP_PX + row * ROW_PX]);
      }
    });
  }

  lengthOf(path) {
    const last = path.keyframe_ids[path.keyframe_ids.length - 1];
    return last === undefined ? 0 : this.index.keyframes[String(last)].distance_m;
  }

  keyAt(x, y) {
    let best = null, bestD2 = (2 * DOT_PX) ** 2;
    for (const [key, [kx, ky]] of this.spots) {
      const d2 = (kx - x) ** 2 + (ky - y) ** 2;
      if (d2 <= bestD2) { best = key; bestD2 = d2; }
    }
    return best;
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    if (!this.index) return;
    ctx.font = "12px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    this.index.paths.forEach((path, row) => {
      const y = TOP_PX + row * ROW_PX;
      ctx.fillStyle = "#333";
      ctx.fillText(`${path.id} ${path.name}`.slice(0, 16), 4, y);
      this.line(path.keyframe_ids, "#90a4ae", 2);
      ctx.fillStyle = "#90a4ae";  // the teach direction
      const [x1] = this.spots.get(path.keyframe_ids[path.keyframe_ids.length - 1]) ?? [0];
      ctx.beginPath(); ctx.moveTo(x1 + 9, y); ctx.lineTo(x1 + 3, y - 4); ctx.lineTo(x1 + 3, y + 4);
      ctx.fill();
    });
    ctx.setLineDash([4, 3]);
    for (const j of this.index.junctions ?? []) this.line([j.from_id, j.to_id], "#8d6e63", 1.5);
    ctx.setLineDash([]);
    this.line(this.route, "#ef6c00", 5);
    for (const [key, [x, y]] of this.spots) {
      ctx.beginPath();
      ctx.arc(x, y, DOT_PX, 0, 2 * Math.PI);
      ctx.fillStyle = key === this.goal ? "#2e7d32" : key === this.next ? "#1565c0"
        : this.route.includes(key) ? "#ef6c00" : "#607d8b";
      ctx.fill();
      if (key === this.chosen) { ctx.strokeStyle = "#000"; ctx.lineWidth = 2; ctx.stroke(); }
    }
  }

  line(keys, color, width) {
    const ctx = this.canvas.getContext("2d");
    const points = keys.map(k => this.spots.get(k)).filter(Boolean);
    if (points.length < 2) return;
    ctx.strokeStyle = color;
    ctx.lineWidth = width;
    ctx.beginPath();
    ctx.moveTo(...points[0]);
    for (const p of points.slice(1)) ctx.lineTo(...p);
    ctx.stroke();
  }
}
