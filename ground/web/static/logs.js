// The ground logs (`vmnav ground --log DIR`): each file with its size and date, to download.

const $ = id => document.getElementById(id);

export async function loadLogs() {
  const response = await fetch("/api/logs", { cache: "no-store" });
  const body = await response.json().catch(() => ({ error: response.statusText }));
  if (!response.ok) { $("log-dir").textContent = `logs: ${body.error}`; return; }
  $("log-dir").textContent = body.dir === null
    ? "no ground log (start with --log DIR)" : `in ${body.dir}`;
  $("log-rows").replaceChildren(...body.files.map(f => {
    const row = document.createElement("tr");
    const link = document.createElement("a");
    link.href = `/api/logs/${encodeURIComponent(f.name)}`;
    link.download = f.name;
    link.textContent = f.name;
    const cells = [link, `${(f.bytes / 1024).toFixed(1)} kB`,
      new Date(f.modified_unix_s * 1000).toLocaleString()];
    for (const content of cells) {
      const cell = document.createElement("td");
      cell.append(content);
      row.append(cell);
    }
    return row;
  }));
}
