// SPDX-License-Identifier: GPL-3.0-or-later
//
// Flamenco job type for blender_turning's headless job (scripts/render_job.py): one task bakes
// the figures once and saves <output_dir>/<job_name>.blend, then frame-chunk tasks render it with
// plain `blender -b <job_name>.blend -s A -e B -a`, each depending on the bake.  The .blend holds
// its output path relative to itself (//frames/frame_), so the frames land next to it.
//
// Install: copy this file into the `scripts` folder next to the flamenco-manager executable and
// restart the Manager (see docs/render-farms.md).  Modelled on Flamenco's built-in
// simple_blender_render.js; the paths are as the Workers see them (shared storage).

const JOB_TYPE = {
    label: "Turning: Bake Once, Render Chunks",
    description: "Bake a blender_turning render-job config once, then render frame chunks",
    settings: [
        { key: "render_job_script", type: "string", subtype: "file_path", required: true,
          description: "scripts/render_job.py of blender_turning, as the Workers see it" },
        { key: "config", type: "string", subtype: "file_path", required: true,
          description: "The job's TOML config (see scripts/configs/)" },
        { key: "output_dir", type: "string", subtype: "dir_path", required: true,
          description: "Folder for <job_name>.blend and frames/ (shared storage)" },
        { key: "job_name", type: "string", required: true,
          description: "Plain file name of the baked .blend (passed as --name)" },
        { key: "frames", type: "string", required: true,
          description: "Frames to render, e.g. '1-241': the job has frames 1 to 1 + seconds * fps" },
        { key: "chunk_size", type: "int32", default: 24, propargs: { min: 1 },
          description: "Frames per render task (a multiple of the config's frame_step)" },
        { key: "device", type: "string", default: "CPU", choices: ["CPU", "GPU"],
          description: "Cycles' render device; GPU makes the bake fail where there is none" },
        { key: "cycles_device", type: "string", default: "",
          description: "GPU backend for the render tasks (OPTIX, CUDA, HIP, ONEAPI, METAL); " +
                       "empty: the Worker's own Blender preferences" },
    ],
};

const GPU_BACKENDS = ["OPTIX", "CUDA", "HIP", "ONEAPI", "METAL"];
// More render tasks than a shot of an hour at 60 fps in chunks of 24 is a mistyped range.
const MAX_CHUNKS = 10000;

function compileJob(job) {
    const settings = job.settings;
    checkSettings(settings);
    const blendfile = path.join(settings.output_dir, `${settings.job_name}.blend`);
    const bake = authorBakeTask(settings);
    job.addTask(bake);
    for (const chunk of frameChunker(settings.frames, settings.chunk_size)) {
        const task = authorRenderTask(settings, blendfile, chunk);
        task.addDependency(bake);
        job.addTask(task);
    }
}

function checkSettings(settings) {
    // One contiguous range, so that every chunk is "A-B" or "A" (a plain -s A -e B).
    const m = /^\s*(\d+)\s*(?:(?:-|\.\.)\s*(\d+)\s*)?$/.exec(`${settings.frames}`);
    if (!m || (m[2] !== undefined && Number(m[2]) < Number(m[1])) || Number(m[1]) < 1) {
        throw `frames = "${settings.frames}" is not one range A-B of frames >= 1 with A <= B`;
    }
    if (!/^[^\/\\.][^\/\\]*$/.test(settings.job_name)) {
        throw `job_name = "${settings.job_name}" is not a plain file name (no folders, not hidden)`;
    }
    if (!(settings.chunk_size >= 1)) {
        throw `chunk_size = ${settings.chunk_size} is not a whole number of frames >= 1`;
    }
    const first = Number(m[1]), last = m[2] === undefined ? first : Number(m[2]);
    const chunks = Math.ceil((last - first + 1) / settings.chunk_size);
    if (chunks > MAX_CHUNKS) {
        throw `frames = "${settings.frames}" in chunks of ${settings.chunk_size} is ${chunks} ` +
              `render tasks; at most ${MAX_CHUNKS}: check the frames against the shot ` +
              `(1 to 1 + seconds * fps) or raise chunk_size`;
    }
    if (settings.device !== "CPU" && settings.device !== "GPU") {
        throw `device = "${settings.device}" is not one of CPU, GPU`;
    }
    if (settings.cycles_device && GPU_BACKENDS.indexOf(settings.cycles_device) < 0) {
        throw `cycles_device = "${settings.cycles_device}" is not one of ${GPU_BACKENDS.join(", ")}`;
    }
}

// The bake: no .blend to open (empty blendfile); render_job.py builds the scene from the config.
function authorBakeTask(settings) {
    const task = author.Task("bake", "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: "",
        args: [
            "--python", settings.render_job_script, "--",
            "--config", settings.config,
            "--no-render",
            "--output", settings.output_dir,
            "--name", settings.job_name,
            "--device", settings.device,
            // The Manager cannot read the config: the bake refuses frames outside the shot,
            // before baking, and no chunk runs.
            "--farm-frames", `${settings.frames}`.replace("..", "-").replace(/\s/g, ""),
        ],
    }));
    return task;
}

// One chunk ("A-B" or "A" from frameChunker): plain `blender -b job.blend -s A -e B -a`.
function authorRenderTask(settings, blendfile, chunk) {
    const [first, last] = chunk.indexOf("-") < 0 ? [chunk, chunk] : chunk.split("-");
    const args = ["-s", first, "-e", last, "-a"];
    if (settings.cycles_device) {
        args.push("--", "--cycles-device", settings.cycles_device);
    }
    const task = author.Task(`render-${chunk}`, "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: blendfile,
        args: args,
    }));
    return task;
}
