"""Run the Flamenco job type (scripts/flamenco/turning_bake_render.js) in node with stand-ins for
the Manager's globals (author, path, frameChunker, print), returning the tasks it authors."""
import json
import shutil
import subprocess

import pytest

from cli_helpers import ROOT

JOB_TYPE = ROOT / "scripts" / "flamenco" / "turning_bake_render.js"

# frameChunker as Flamenco's Go JSFrameChunker does it for one contiguous range: at most
# chunk_size frames a chunk, "A-B" (or "A" for one frame).
_HARNESS = r"""
const fs = require("fs"), vm = require("vm"), nodePath = require("path");
const [file, settingsJson] = process.argv.slice(1);
function frameChunker(range, size) {
  const m = /^\s*(\d+)\s*(?:(?:-|\.\.)\s*(\d+)\s*)?$/.exec(range);
  if (!m) throw `frameChunker stand-in: ${range}`;
  const a = Number(m[1]), b = m[2] === undefined ? a : Number(m[2]), out = [];
  for (let s = a; s <= b; s += size) {
    const e = Math.min(s + size - 1, b);
    out.push(s === e ? `${s}` : `${s}-${e}`);
  }
  return out;
}
const author = {
  Task: (name, type) => ({ name, type, commands: [], deps: [],
    addCommand(c) { this.commands.push(c); }, addDependency(t) { this.deps.push(t.name); } }),
  Command: (name, parameters) => ({ name, parameters }),
};
const ctx = { author, frameChunker, print: () => {}, path: nodePath.posix };
vm.createContext(ctx);
vm.runInContext(fs.readFileSync(file, "utf8") + "\nthis.JOB_TYPE = JOB_TYPE;", ctx);
const job = { settings: JSON.parse(settingsJson), tasks: [], addTask(t) { this.tasks.push(t); } };
try {
  ctx.compileJob(job);
} catch (e) {
  console.log(JSON.stringify({ error: String(e) }));
  process.exit(0);
}
console.log(JSON.stringify({ job_type: ctx.JOB_TYPE, tasks: job.tasks.map(
  t => ({ name: t.name, type: t.type, commands: t.commands, deps: t.deps })) }));
"""


def node():
    exe = shutil.which("node")
    if exe is None:
        pytest.skip("node is not installed: the Flamenco job type (JavaScript) cannot be run")
    return exe


def compile_job(settings: dict) -> dict:
    r = subprocess.run([node(), "-e", _HARNESS, str(JOB_TYPE), json.dumps(settings)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)
