//! One file through the camera, as every front end applies it (the command
//! line, the studio's export, Python's `apply_file`): the output checked
//! before any work, the file read as a frame, the camera applied to every
//! view of it, the result written into a copy of the input. A guard added
//! here holds in each of them.

use std::path::Path;

use aureole::{Applied, ApplyOptions, Frame, FrameOptions, Image, Session, Stage};

use crate::atomic::folder_of;
use crate::error::{Error, Result};
use crate::formats::Original;
use crate::limits::Limits;
use crate::read::{read_image_with, Choice, Loaded};
use crate::write::{output_format, refuse_overwrite, write_image_into, WriteOptions, Written};

/// Refuses, before any work, an output whose extension names no format
/// we write, that would overwrite `input`, that is not a plain file, or
/// whose folder is missing or cannot be written (a probe file is made and
/// removed there).
pub fn check_output(output: &Path, input: Option<&Path>) -> Result<()> {
    output_format(output)?;
    if let Some(input) = input {
        refuse_overwrite(output, input)?;
    }
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

/// Refuses, before any work, glare layers for an output whose format
/// cannot hold them: only OpenEXR has layers.
pub fn check_layers_output(output: &Path) -> Result<()> {
    if crate::formats::by_extension(output).is_some_and(|format| format.layers) {
        return Ok(());
    }
    let (names, extensions) = crate::formats::layered_outputs();
    Err(Error::Output {
        path: output.to_path_buf(),
        reason: format!("glare layers are written only into {names}; write to a {extensions} file"),
    })
}

/// Refuses, from its header and before it is decoded, a file whose frame
/// `session` could not take: one that needs more memory than its limit,
/// or a kernel beyond the largest allowed (`Error::Content` with the
/// library's reason); a header that does not say passes, and reading the
/// file then says what is wrong with it.
pub fn check_header(path: &Path, choice: &Choice, limits: Limits, session: &Session) -> Result<()> {
    if let Some(shape) = crate::read::probe(path, limits, choice)? {
        session.check_shape(shape).map_err(|error| Error::Content {
            path: path.to_path_buf(),
            error,
        })?;
    }
    Ok(())
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

/// Reads `path` (the layer and part `choice` names) as a frame.
pub fn read(path: &Path, choice: &Choice, limits: Limits, options: &FrameOptions) -> Result<Input> {
    let loaded = read_image_with(path, limits, choice)?;
    input(path, loaded, options)
}

/// A file already read, as a frame.
pub fn input(path: &Path, mut loaded: Loaded, options: &FrameOptions) -> Result<Input> {
    let original = std::mem::take(&mut loaded.original);
    let frame = Frame::new(loaded.image, options).map_err(|error| Error::Content {
        path: path.to_path_buf(),
        error,
    })?;
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
        self.apply_views(session, options, report)?;
        Ok(applied)
    }

    /// The camera applied to each other view, its result replacing it.
    fn apply_views(
        &mut self,
        session: &mut Session,
        options: &ApplyOptions,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<()> {
        // The views share the frame's scale: they are one exposure.
        let views = FrameOptions {
            input_scale: Some(self.frame.scale()),
            ..self.options
        };
        for (_, image) in self.original.views_mut() {
            let empty = Image::filled(0, 0, image.layout, 0.0);
            let frame = Frame::new(std::mem::replace(image, empty), &views)?;
            *image = session.apply(&frame, options, report)?.image;
        }
        Ok(())
    }

    /// [`Input::apply`], with the light each effect adds kept as layers
    /// ([`aureole::Session::apply_layers`]) that [`Input::write`] puts
    /// beside the frame's result; the other views get the beauty alone.
    pub fn apply_layers(
        &mut self,
        session: &mut Session,
        options: &ApplyOptions,
        report: &mut dyn FnMut(Stage, f64),
    ) -> aureole::Result<Applied> {
        let (applied, layers) = session.apply_layers(&self.frame, options, report)?;
        self.apply_views(session, options, report)?;
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
