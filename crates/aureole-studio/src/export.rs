//! Full-resolution renders to a file under the roots, as jobs the page
//! follows: the same session, options and writer as `aureole apply`, with
//! the stage and fraction done, and a cancel.

use aureole::Device;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use aureole::{Cancel, FrameOptions, Session};
use aureole_io::job::Input;
use aureole_io::limits::Limits;
use aureole_io::write::{output_format, WriteOptions};
use serde::Serialize;

use crate::budget::Budget;
use crate::error::StudioError;
use crate::locked;
use crate::render::{
    display_options, max_extent, needs, needs_for, parse_config, RenderRequest, DEMO,
};
use crate::roots::Roots;

/// `POST /api/export`: a render request's fields (without `width`),
/// `output`, where to write the full-resolution result, and `overwrite`,
/// whether a file already there may be replaced (by default it is not).
#[derive(Debug, Clone)]
pub struct ExportRequest {
    /// The camera, image and display settings, as for a preview.
    pub render: RenderRequest,
    /// The file to write, under a root (absolute, or relative to the first
    /// root); its extension chooses the format, as for `aureole apply -o`.
    pub output: String,
    /// Whether an existing file at `output` may be replaced.
    pub overwrite: bool,
    /// Whether the light each effect adds goes beside the result, as
    /// layers of the output EXR (`aureole apply --layers`).
    pub layers: bool,
}

impl ExportRequest {
    /// Reads the JSON of a request.
    pub fn from_json(bytes: &[u8]) -> Result<ExportRequest, StudioError> {
        let refuse = |e: String| StudioError::BadRequest(format!("the export request: {e}"));
        let mut value: serde_json::Value =
            serde_json::from_slice(bytes).map_err(|e| refuse(e.to_string()))?;
        let fields = value
            .as_object_mut()
            .ok_or_else(|| refuse("expected a JSON object".into()))?;
        let output = match fields.remove("output") {
            Some(serde_json::Value::String(output)) => output,
            _ => return Err(refuse("`output`, the file to write, is missing".into())),
        };
        let overwrite = match fields.remove("overwrite") {
            None => false,
            Some(serde_json::Value::Bool(overwrite)) => overwrite,
            Some(other) => return Err(refuse(format!("`overwrite` is {other}: true or false"))),
        };
        let layers = match fields.remove("layers") {
            None => false,
            Some(serde_json::Value::Bool(layers)) => layers,
            Some(other) => return Err(refuse(format!("`layers` is {other}: true or false"))),
        };
        // The full image is rendered: the preview's width does not apply.
        fields.insert("width".into(), serde_json::Value::from(1));
        let render = serde_json::from_value(value).map_err(|e| refuse(e.to_string()))?;
        Ok(ExportRequest {
            render,
            output,
            overwrite,
            layers,
        })
    }
}

/// What a job has done so far.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Progress {
    /// The stage, in words.
    pub stage: String,
    /// The fraction of the stage done, 0…1.
    pub fraction: f64,
    /// Whether it has ended, written or not.
    pub done: bool,
    /// Why it failed, in one line.
    pub error: Option<String>,
    /// The file written.
    pub output: String,
    /// How the file was read and written, a line each, as the command
    /// line says them (ignored layers, channels a format could not keep).
    pub notes: Vec<String>,
}

struct Export {
    progress: Mutex<Progress>,
    cancel: Cancel,
}

/// The export jobs of a studio.
pub struct Exports {
    roots: Roots,
    budget: Arc<Budget>,
    device: Device,
    next: AtomicU64,
    jobs: Mutex<HashMap<u64, Arc<Export>>>,
}

impl Exports {
    /// Jobs that read and write under `roots`, within `budget`, which
    /// previews share.
    pub fn new(roots: Roots, budget: Arc<Budget>, device: Device) -> Exports {
        Exports {
            roots,
            budget,
            device,
            next: AtomicU64::new(1),
            jobs: Mutex::new(HashMap::new()),
        }
    }

    /// Checks `request` and starts it on a thread of its own; returns its
    /// number.
    pub fn start(&self, request: ExportRequest) -> Result<u64, StudioError> {
        let config = parse_config(&request.render.config)?;
        let display = display_options(&request.render)?;
        let max_extent = max_extent(&request.render)?;
        let input = match request.render.image.as_str() {
            DEMO => None,
            name => Some(self.roots.resolve(name)?),
        };
        let output = self.output_path(&request.output)?;
        let job = aureole_io::job::Job {
            input,
            output,
            choice: Default::default(),
            frame: FrameOptions::default(),
            options: request.render.options()?,
            layers: request.layers,
            write: WriteOptions {
                linear: Default::default(),
                display,
                depth: None,
            },
        };
        // What every front end checks before the work, in the same words.
        job.check()
            .map_err(|e| StudioError::BadRequest(e.to_string()))?;
        if !request.overwrite && job.output.symlink_metadata().is_ok() {
            return Err(StudioError::Conflict(exists(&request.output)));
        }
        let id = self.next.fetch_add(1, Ordering::Relaxed);
        let export = Arc::new(Export {
            progress: Mutex::new(Progress {
                stage: "reading".into(),
                output: job.output.display().to_string(),
                ..Progress::default()
            }),
            cancel: Cancel::new(),
        });
        locked(&self.jobs).insert(id, export.clone());
        let budget = self.budget.clone();
        let device = self.device;
        std::thread::spawn(move || {
            let target = Target {
                overwrite: request.overwrite,
                max_extent,
                device,
            };
            let outcome = run(&export, &job, config, target, &budget);
            let mut progress = locked(&export.progress);
            progress.done = true;
            if let Err(error) = outcome {
                progress.error = Some(error.to_string().replace('\n', " "));
            } else {
                progress.fraction = 1.0;
                progress.stage = "written".into();
            }
        });
        Ok(id)
    }

    /// Where job `id` stands.
    pub fn progress(&self, id: u64) -> Option<Progress> {
        let jobs = locked(&self.jobs);
        let job = jobs.get(&id)?;
        let progress = locked(&job.progress).clone();
        Some(progress)
    }

    /// Stops job `id`; its file is not written.
    pub fn cancel(&self, id: u64) -> bool {
        match locked(&self.jobs).get(&id) {
            Some(job) => {
                job.cancel.cancel();
                true
            }
            None => false,
        }
    }

    /// The file `requested` names, in a folder under a root, in a format
    /// we write.
    fn output_path(&self, requested: &str) -> Result<PathBuf, StudioError> {
        let path = Path::new(requested);
        let path = match self.roots.folders().first() {
            Some(root) if path.is_relative() => root.join(path),
            _ => path.to_path_buf(),
        };
        output_format(&path).map_err(|e| StudioError::BadRequest(e.to_string()))?;
        let folder = aureole_io::atomic::folder_of(&path);
        let name = path
            .file_name()
            .ok_or_else(|| StudioError::BadRequest(format!("{requested}: names no file")))?;
        let folder = folder.canonicalize().map_err(|_| {
            StudioError::NotFound(format!("{requested}: its folder does not exist"))
        })?;
        if !self
            .roots
            .folders()
            .iter()
            .any(|root| folder.starts_with(root))
        {
            return Err(StudioError::Forbidden(format!(
                "{requested}: is outside the folders the studio may write"
            )));
        }
        // That it is a plain file in a folder that can be written is the
        // one job's check (`job::check_output`), as for every front end.
        Ok(folder.join(name))
    }
}

fn exists(requested: &str) -> String {
    format!(
        "{requested}: exists; choose another name, or ask with \"overwrite\": true to replace it"
    )
}

/// How an export runs.
struct Target {
    overwrite: bool,
    max_extent: Option<(usize, usize)>,
    device: Device,
}

fn run(
    export: &Export,
    job: &aureole_io::job::Job,
    config: aureole::Config,
    target: Target,
    budget: &Arc<Budget>,
) -> Result<(), StudioError> {
    let memory_limit = budget.total();
    let Target {
        overwrite,
        max_extent,
        device,
    } = target;
    let limits = Limits {
        max_bytes: memory_limit,
    };
    let mut session = Session::new(config.clone())
        .with_memory_limit(memory_limit)
        .with_max_extent(max_extent)
        .with_device(device);
    session.set_cancel_token(export.cancel.clone());
    let lease = |bytes| {
        budget.lease(bytes, &export.cancel, None, || {
            locked(&export.progress).stage = "waiting for memory".into();
        })
    };
    let (mut input, _lease) = match &job.input {
        None => {
            let input = Input::from_image(aureole_io::demo::night_street(1280, 720), &job.frame)?;
            let bytes = needs(&config, &input.frame, max_extent, job.layers)?;
            (input, lease(bytes)?)
        }
        // A frame the camera could not take is refused from its header,
        // and its memory is taken before it is decoded where the header
        // says its size: parallel exports of large files wait rather than
        // decode beside each other.
        Some(_) => {
            let (input, early) = job.read(&session, limits, |shape| {
                shape
                    .map(|shape| lease(needs_for(&config, shape, max_extent, job.layers)?))
                    .transpose()
            })?;
            let held = match early {
                Some(held) => held,
                None => lease(needs(&config, &input.frame, max_extent, job.layers)?)?,
            };
            (input, held)
        }
    };
    let mut report = |stage: aureole::Stage, fraction| {
        let mut progress = locked(&export.progress);
        progress.stage = stage.describe().to_string();
        progress.fraction = fraction;
    };
    // A stereo plate's every view goes through the camera.
    let applied = job.apply(&mut input, &mut session, &mut report)?;
    export.cancel.check()?;
    locked(&export.progress).stage = "writing".into();
    // Another program may have made the file while the camera ran.
    if !overwrite && job.output.symlink_metadata().is_ok() {
        return Err(StudioError::Conflict(exists(
            &job.output.display().to_string(),
        )));
    }
    let done = job.write(input, applied)?;
    locked(&export.progress).notes = done.notes;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An export takes its memory before it decodes: with the budget held
    /// elsewhere, an export of a file whose header says its size waits for
    /// memory before reading its pixels. A file whose pixels are cut off
    /// tells the order: decoded first, it would fail at once.
    #[test]
    fn an_export_takes_its_memory_before_decoding() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.exr");
        let image = aureole_io::demo::night_street(640, 360);
        aureole_io::write::write_linear(&path, &image, Default::default()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let budget = Budget::new(256 << 20);
        let held = budget
            .lease(budget.total(), &Cancel::new(), None, || {})
            .unwrap();
        let roots = Roots::new(&[dir.path().to_path_buf()]).unwrap();
        let exports = Exports::new(roots, budget.clone(), Device::Cpu);
        let request = ExportRequest::from_json(
            format!(
                r#"{{"image": "cut.exr", "config": {}, "output": "out.exr"}}"#,
                serde_json::to_string(aureole::presets::find("paper-fig4-bloom").unwrap().toml)
                    .unwrap()
            )
            .as_bytes(),
        )
        .unwrap();
        let id = exports.start(request).unwrap();
        let progress = loop {
            let progress = exports.progress(id).unwrap();
            if progress.done || progress.stage == "waiting for memory" {
                break progress;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert_eq!(progress.stage, "waiting for memory", "{progress:?}");
        // Given the memory, it reads the file and says what is wrong.
        drop(held);
        let progress = loop {
            let progress = exports.progress(id).unwrap();
            if progress.done {
                break progress;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        let error = progress.error.unwrap_or_default();
        assert!(error.contains("cut.exr"), "{error}");
        assert!(!dir.path().join("out.exr").exists());
    }
}
