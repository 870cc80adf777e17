//! One file through the camera, as every front end applies it (the command
//! line, the studio's export, Python's `apply_file`): the output checked
//! before any work, the file read as a frame, the camera applied to every
//! view of it, the result written into a copy of the input. A guard added
//! here holds in each of them.

use std::path::{Path, PathBuf};

use aureole::image::Shape;
use aureole::{Applied, ApplyOptions, Frame, FrameOptions, Image, Session, Stage};

use crate::atomic::folder_of;
use crate::error::{Error, Result};
use crate::formats::{Kind, Original};
use crate::limits::Limits;
use crate::read::{read_image_reusing, Choice, Loaded};
use crate::spares::Spares;
use crate::write::Written;
use crate::write::{output_format, refuse_overwrite, write_image_into, WriteOptions};

/// Refuses, before any work, an output whose extension names no format
/// we write, that would overwrite `input`, that is not a plain file, or
/// whose folder is missing or cannot be written (a probe file is made and
/// removed there).
pub fn check_output(output: &Path, input: Option<&Path>) -> Result<()> {
    output_format(output)?;
    if let Some(input) = input {
        refuse_overwrite(output, input)?;
    }
    check_folder(output)
}

/// Refuses, before any work, an output that is not a plain file or whose
/// folder is missing or cannot be written (a probe file is made and
/// removed there): for outputs whose format is checked apart (kernels,
/// plots, lenses).
pub fn check_folder(output: &Path) -> Result<()> {
    let refuse = |reason: String| Error::Output {
        path: output.to_path_buf(),
        reason,
    };
    let folder = folder_of(output);
    if !folder.is_dir() {
        return Err(refuse(format!(
            "the output folder {} does not exist; create it first",
            folder.display()
        )));
    }
    // The result replaces a file by renaming over it, which would replace
    // a device or a named pipe by a file.
    if std::fs::metadata(output).is_ok_and(|meta| !meta.is_file()) {
        return Err(refuse(
            "exists and is not a plain file (a folder, device or pipe); write to a file".into(),
        ));
    }
    tempfile::Builder::new()
        .prefix(".aureole-probe-")
        .tempfile_in(folder)
        .map(drop)
        .map_err(|e| {
            refuse(format!(
                "cannot write in the folder {}: {}",
                folder.display(),
                aureole::error::describe_io(&std::io::Error::from(e.kind()))
            ))
        })
}

/// Why glare layers and a glare-only result are not asked together, for
/// every front end that can ask both.
pub const LAYERS_WITH_GLARE_ONLY: &str =
    "glare layers go beside the result, and a glare-only result has none: ask for the layers or for the glare alone";

/// What a front end asks of one file: the output, the input it is made
/// from (none for an image made in memory), how the camera is applied and
/// whether the glare layers go beside the result. [`Request::check`]
/// refuses, before any work, everything the command line, the studio's
/// export and Python refuse, in the same words.
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    /// The file to write.
    pub output: &'a Path,
    /// The file read, which the output must not overwrite.
    pub input: Option<&'a Path>,
    /// The threshold, knee, glare-only and method.
    pub options: &'a ApplyOptions,
    /// Whether the light each effect adds goes beside the result.
    pub layers: bool,
}

impl Request<'_> {
    /// Refuses options outside their ranges ([`ApplyOptions::check`]), an
    /// output [`check_output`] refuses, glare layers with a glare-only
    /// result or into a format without layers, and a glare-only result
    /// into a linear format without negative values: adding such a file
    /// back over the plate would create light where the camera took it
    /// away.
    pub fn check(&self) -> Result<()> {
        self.check_asked()?;
        check_output(self.output, self.input)
    }

    /// The checks of [`Request::check`] that read no file system: what a
    /// command line for the request would be refused for, wherever it
    /// runs, and a name no file system takes.
    pub fn check_asked(&self) -> Result<()> {
        self.options.check().map_err(Error::Options)?;
        let refuse = |reason: String| Error::Refused {
            path: self.output.to_path_buf(),
            reason,
        };
        // No file system takes a NUL in a name; without this a render runs
        // to its end before the write is refused.
        if self.output.as_os_str().as_encoded_bytes().contains(&0) {
            return Err(refuse(
                "the name holds a NUL character, which no file system takes; name the file without it".into(),
            ));
        }
        let format = output_format(self.output)?;
        if self.layers && self.options.glare_only {
            return Err(refuse(LAYERS_WITH_GLARE_ONLY.into()));
        }
        if self.layers && !format.layers {
            let (names, extensions) = crate::formats::layered_outputs();
            return Err(refuse(format!(
                "glare layers are written only into {names}; write to a {extensions} file"
            )));
        }
        if self.options.glare_only && format.kind() == Kind::Linear && !format.signed {
            return Err(refuse(format!(
                "{} holds no negative values, which a glare-only result has (light moved away from the sources); write {}",
                format.name,
                crate::formats::signed_outputs()
            )));
        }
        Ok(())
    }
}

/// Refuses, from its header and before it is decoded, a file whose frame
/// `session` could not take: one that needs more memory than its limit,
/// or a kernel beyond the largest allowed (`Error::Content` with the
/// library's reason); a header that does not say passes, and reading the
/// file then says what is wrong with it. Returns the frame's shape where
/// the header says it, for a memory budget to be taken before decoding.
pub fn check_header(
    path: &Path,
    choice: &Choice,
    limits: Limits,
    session: &Session,
) -> Result<Option<Shape>> {
    let shape = crate::read::probe(path, limits, choice)?;
    if let Some(shape) = shape {
        session.check_shape(shape).map_err(|error| Error::Content {
            path: path.to_path_buf(),
            error,
        })?;
    }
    Ok(shape)
}

/// A file read for the camera: its frame, the rest of the file (other
/// layers, parts, views, attributes) and what the user should know.
pub struct Input {
    /// The chosen layer as a frame, its luminance scale decided.
    pub frame: Frame,
    /// The rest of the file, the other views' images among it.
    pub original: Original,
    /// How the file was read, a line each (ignored layers, …).
    pub notes: Vec<String>,
    /// The file's format, in words.
    pub format: &'static str,
    /// An 8/16-bit display image, whose luminance is only relative.
    pub display_referred: bool,
    /// How the frame was made, for the other views.
    options: FrameOptions,
}

/// A file already read, as a frame.
pub fn input(path: &Path, mut loaded: Loaded, options: &FrameOptions) -> Result<Input> {
    let original = std::mem::take(&mut loaded.original);
    let frame = Frame::new(loaded.image, options).map_err(|error| Error::Content {
        path: path.to_path_buf(),
        error,
    })?;
    let frame = match original.display_window() {
        Some(window) => frame.with_display_window(window),
        None => frame,
    };
    Ok(Input {
        frame,
        original,
        notes: loaded.notes,
        format: loaded.format,
        display_referred: loaded.display_referred,
        options: *options,
    })
}

impl Input {
    /// An image made in memory (the demo scene), as a file read would be.
    pub fn from_image(image: Image, options: &FrameOptions) -> aureole::Result<Input> {
        Ok(Input {
            frame: Frame::new(image, options)?,
            original: Original::default(),
            notes: Vec::new(),
            format: "image",
            display_referred: false,
            options: *options,
        })
    }

    /// The camera of `session` applied to the frame and then to every
    /// other view of the file (a stereo plate's second eye), each view as
    /// one frame through the same camera; returns the frame's result, the
    /// other views' replacing their images in [`Input::original`].
    pub fn apply(
        &mut self,
        session: &mut Session,
        options: &ApplyOptions,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<Applied> {
        let applied = session.apply(&self.frame, options, report)?;
        self.apply_views(session, options, false, report)?;
        Ok(applied)
    }

    /// The camera applied to each other view, its result replacing it;
    /// with `layers`, each view's glare layers kept beside it.
    fn apply_views(
        &mut self,
        session: &mut Session,
        options: &ApplyOptions,
        layers: bool,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<()> {
        // The views share the frame's scale: they are one exposure.
        let views = FrameOptions {
            input_scale: Some(self.frame.scale()),
            ..self.options
        };
        // A view's pixels are the frame's own window's.
        let window = self.frame.display_window();
        for (image, glare) in self.original.views_mut() {
            let empty = Image::filled(0, 0, image.layout, 0.0);
            let frame =
                Frame::new(std::mem::replace(image, empty), &views)?.with_display_window(window);
            *image = if layers {
                let (applied, view_layers) = session.apply_layers(&frame, options, report)?;
                *glare = view_layers;
                applied.image
            } else {
                session.apply(&frame, options, report)?.image
            };
        }
        Ok(())
    }

    /// [`Input::apply`], with the light each effect adds kept as layers
    /// ([`aureole::Session::apply_layers`]) that [`Input::write`] puts
    /// beside each view's result.
    pub fn apply_layers(
        &mut self,
        session: &mut Session,
        options: &ApplyOptions,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<Applied> {
        let (applied, layers) = session.apply_layers(&self.frame, options, report)?;
        self.apply_views(session, options, true, report)?;
        self.original.add_glare_layers(layers);
        Ok(applied)
    }

    /// Hands the frame's planes to the buffers the file was read with
    /// ([`crate::read::read_image_reusing`]) once every view has been
    /// through the camera: the next frame is decoded into them. The frame
    /// is empty afterwards; [`Input::write`] needs only its scale.
    pub fn give_back_planes(&mut self) {
        self.original.spares.give_image(self.frame.take_image());
    }

    /// Writes `image`, the camera's result, to `output` atomically: an EXR
    /// into a copy of the input with every view, layer, part and attribute,
    /// a linear format as it is, a picture exposed and tone-mapped.
    pub fn write(self, output: &Path, image: &Image, options: &WriteOptions) -> Result<Written> {
        write_image_into(output, image, self.frame.scale(), options, self.original)
    }
}

/// One file through the camera, as every front end asks it: the input
/// (none for an image made in memory), the output, the layer and part
/// read, how the frame is made, how the camera is applied, whether the
/// glare layers go beside the result, and how it is written. Checked
/// before any work ([`Job::check`]), then read ([`Job::read`]), applied
/// ([`Job::apply`]) and written ([`Job::write`]), or all three by
/// [`Job::run`]. The command line's batch pipelines the phases (each
/// frame decoded while the one before is convolved, [`Job::decode`]); the
/// studio's export and Python run them with their own memory lease and
/// progress between.
#[derive(Debug, Clone)]
pub struct Job {
    /// The file read, which the output must not overwrite.
    pub input: Option<PathBuf>,
    /// The file written.
    pub output: PathBuf,
    /// The layer and part of the input.
    pub choice: Choice,
    /// How the input becomes a frame (its cd/m² per unit).
    pub frame: FrameOptions,
    /// The threshold, knee, glare-only and method.
    pub options: ApplyOptions,
    /// Whether the light each effect adds goes beside the result.
    pub layers: bool,
    /// How the result is written.
    pub write: WriteOptions,
}

/// What a job made: the camera's result, the frame's cd/m² per unit,
/// what the writer made, and what the user should know (the reader's and
/// the writer's notes, a line each).
#[derive(Debug)]
pub struct Done {
    /// The camera's result.
    pub applied: Applied,
    /// The frame's luminance scale, cd/m² per unit.
    pub scale: f64,
    /// What the writer made.
    pub written: Written,
    /// Notes for the user.
    pub notes: Vec<String>,
}

impl Job {
    /// What the job asks, for [`Request::check`] and its words.
    pub fn request(&self) -> Request<'_> {
        Request {
            output: &self.output,
            input: self.input.as_deref(),
            options: &self.options,
            layers: self.layers,
        }
    }

    /// Every check before any work ([`Request::check`]).
    pub fn check(&self) -> Result<()> {
        self.request().check()
    }

    /// The input read as a frame: refused from its header where `session`
    /// could not take it ([`Job::check_header`]), and `before_decoding`
    /// called with the header's shape (`None` where it does not say)
    /// before the pixels are decoded ([`Job::decode`]), for a memory lease
    /// to be taken there; returns the frame and what `before_decoding`
    /// returned.
    pub fn read<T, E: From<Error>>(
        &self,
        session: &Session,
        limits: Limits,
        before_decoding: impl FnOnce(Option<Shape>) -> std::result::Result<T, E>,
    ) -> std::result::Result<(Input, T), E> {
        let shape = self.check_header(session, limits)?;
        let held = before_decoding(shape)?;
        Ok((self.decode(limits, &Spares::default())?, held))
    }

    /// Refuses the input from its header where `session` could not take
    /// its frame ([`check_header`]); returns the frame's shape where the
    /// header says it.
    pub fn check_header(&self, session: &Session, limits: Limits) -> Result<Option<Shape>> {
        check_header(self.input_path()?, &self.choice, limits, session)
    }

    /// The input decoded as a frame, into the buffers `spares` lends (the
    /// frames' before it in a batch), without the header's check: a batch
    /// checks its first frame's header against the session, then decodes
    /// each frame on a thread of its own while the session convolves the
    /// one before.
    pub fn decode(&self, limits: Limits, spares: &Spares) -> Result<Input> {
        let path = self.input_path()?;
        let loaded = read_image_reusing(path, limits, &self.choice, spares)?;
        input(path, loaded, &self.frame)
    }

    /// The file the job is about, for the user's messages: its input,
    /// else (an image made in memory) its output.
    pub fn file(&self) -> &Path {
        self.input.as_deref().unwrap_or(&self.output)
    }

    fn input_path(&self) -> Result<&Path> {
        self.input.as_deref().ok_or_else(|| Error::Refused {
            path: self.output.clone(),
            reason: "the job has no input file to read".into(),
        })
    }

    /// The camera of `session` applied to every view of `input`, with the
    /// glare layers kept where the job asks for them.
    pub fn apply(
        &self,
        input: &mut Input,
        session: &mut Session,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<Applied> {
        if self.layers {
            input.apply_layers(session, &self.options, report)
        } else {
            input.apply(session, &self.options, report)
        }
    }

    /// `applied` written into a copy of `input` ([`Input::write`]).
    pub fn write(&self, mut input: Input, applied: Applied) -> Result<Done> {
        let mut notes = std::mem::take(&mut input.notes);
        let scale = input.frame.scale();
        let written = input.write(&self.output, &applied.image, &self.write)?;
        if let Written::Linear(more) = &written {
            notes.extend(more.iter().map(ToString::to_string));
        }
        Ok(Done {
            applied,
            scale,
            written,
            notes,
        })
    }

    /// The whole job: checked, read, applied and written.
    pub fn run(
        &self,
        session: &mut Session,
        limits: Limits,
        report: &mut dyn FnMut(Stage, f64),
    ) -> Result<Done> {
        self.check()?;
        let (mut input, ()) = self.read(session, limits, |_| Ok::<(), Error>(()))?;
        let applied = self
            .apply(&mut input, session, report)
            .map_err(|error| Error::Content {
                path: self.file().to_path_buf(),
                error,
            })?;
        self.write(input, applied)
    }
}
