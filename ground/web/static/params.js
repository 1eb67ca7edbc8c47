// The robot's parameters: load them all, edit one (PARAM_SET; the value in force comes back).

const $ = id => document.getElementById(id);

export class ParamsTable {
  constructor(app) {
    this.app = app;
    $("params-load").onclick = () => this.load();
  }

  async load() {
    const reply = await this.app.command("params");
    if (!reply.ok) return;
    const rows = Object.entries(reply.params).map(([name, value]) => {
      const row = document.createElement("tr");
      row.dataset.param = name;
      const label = document.createElement("td");
      label.textContent = name;
      const input = document.createElement("input");
      input.value = String(value);
      input.size = 10;
      const button = document.createElement("button");
      button.textContent = "Set";
      button.onclick = async () => {
        const done = await this.app.command("param_set", { name, value: Number(input.value) });
        if (done.ok) input.value = String(done.value);
      };
      const cell = document.createElement("td");
      cell.append(input, " ", button);
      row.append(label, cell);
      return row;
    });
    $("param-rows").replaceChildren(...rows);
  }
}
