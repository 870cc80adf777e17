//! What the studio keeps between renders: the last full image, its
//! preview, and the session of the last camera at that preview's size.

use std::sync::Arc;
use std::time::SystemTime;

use std::sync::atomic::Ordering;

use aureole::{Cancel, Frame, FrameOptions, Image, Session};
use aureole_io::limits::Limits;

use super::{needs, no_rays, parse_config, Renderer, Summary, DEMO, PATIENCE};
use crate::budget::Lease;
use crate::error::StudioError;
use crate::locked;

/// A full image in memory, with where it came from.
pub(super) struct Loaded {
    key: (String, Option<SystemTime>),
    frame: Arc<Frame>,
    summary: Summary,
}

/// A preview: the full frame it was made from, its width, and the
/// resampled frame.
pub(super) struct Preview {
    source: Arc<Frame>,
    width: usize,
    frame: Arc<Frame>,
}

/// The most sessions kept: going back to a camera tried a moment ago (the
/// dusty lens and the clean one, say) reuses its kernel.
pub(super) const KEPT: usize = 4;

/// The session of a recent config and preview size, kept so that a change
/// of threshold or exposure, or a return to that camera, reuses its kernel
/// and spectra.
pub(super) struct KeptSession {
    pub key: SessionKey,
    pub session: Session,
    /// Its memory, counted in the budget while it is kept.
    pub _lease: Lease,
}

/// A session's config, preview size and kernel cap.
pub(super) type SessionKey = ((String, (usize, usize)), Option<(usize, usize)>);

impl Renderer {
    /// Gives the kept session's memory back to the budget, unless a render
    /// is using it.
    pub fn release_kept(&self) {
        if let Ok(mut kept) = self.kept.try_lock() {
            kept.clear();
        }
        if let Ok(mut rays) = self.rays.try_lock() {
            *rays = no_rays(&self.budget);
        }
    }

    /// The kept sessions, the one for `key` first: kept from before, or
    /// made for `config` (its lengths scaled by `factor` to the preview)
    /// with its memory leased. The least recent go, their memory back to
    /// the budget, while the budget lacks room for the new one, and beyond
    /// [`KEPT`].
    pub(super) fn kept_session(
        &self,
        key: SessionKey,
        config: &str,
        preview: &Frame,
        factor: f64,
        cancel: &Cancel,
    ) -> Result<std::sync::MutexGuard<'_, Vec<KeptSession>>, StudioError> {
        let mut kept = locked(&self.kept);
        if let Some(index) = kept.iter().position(|c| c.key == key) {
            kept[..=index].rotate_right(1);
            self.reused.fetch_add(1, Ordering::Relaxed);
            return Ok(kept);
        }
        let max_extent = key.1;
        let config = parse_config(config)?.with_pixels_scaled(factor);
        let bytes = needs(&config, preview, max_extent, false)?;
        kept.truncate(KEPT - 1);
        while !kept.is_empty() && self.budget.available() < bytes {
            kept.pop();
        }
        let lease = self.budget.lease(bytes, cancel, Some(PATIENCE), || {})?;
        let session = Session::new(config)
            .with_memory_limit(self.budget.total())
            .with_max_extent(max_extent)
            .with_device(self.device);
        kept.insert(
            0,
            KeptSession {
                key,
                session,
                _lease: lease,
            },
        );
        Ok(kept)
    }

    /// The full image `name` names, read once while it does not change.
    pub(super) fn load(&self, name: &str) -> Result<(Arc<Frame>, Summary), StudioError> {
        let (path, modified) = if name == DEMO {
            (None, None)
        } else {
            let path = self.roots.resolve(name)?;
            let modified = std::fs::metadata(&path).and_then(|m| m.modified()).ok();
            (Some(path), modified)
        };
        let key = (name.to_string(), modified);
        let mut loaded = locked(&self.loaded);
        if let Some(hit) = loaded.as_ref().filter(|l| l.key == key) {
            return Ok((hit.frame.clone(), hit.summary));
        }
        let image = match &path {
            None => aureole_io::demo::night_street(1280, 720),
            Some(path) => read(path, self.budget.total())?,
        };
        let frame = Arc::new(
            Frame::new(image, &FrameOptions::default())
                .map_err(|e| StudioError::Unprocessable(format!("{name}: {e}")))?,
        );
        let summary = Summary::of(&frame);
        *loaded = Some(Loaded {
            key,
            frame: frame.clone(),
            summary,
        });
        Ok((frame, summary))
    }

    /// `full` resampled by area to `width` (no wider than it is).
    pub(super) fn preview(
        &self,
        full: &Arc<Frame>,
        width: usize,
    ) -> Result<Arc<Frame>, StudioError> {
        let image = full.image();
        let width = width.min(image.width);
        let height =
            ((image.height as f64 * width as f64 / image.width as f64).round() as usize).max(1);
        let mut preview = locked(&self.preview);
        let hit = |p: &&Preview| Arc::ptr_eq(&p.source, full) && p.width == width;
        if let Some(hit) = preview.as_ref().filter(hit) {
            return Ok(hit.frame.clone());
        }
        let options = FrameOptions {
            input_scale: Some(full.scale()),
            sanitize: false,
        };
        let frame = Arc::new(Frame::new(image.resampled(width, height), &options)?);
        *preview = Some(Preview {
            source: full.clone(),
            width,
            frame: frame.clone(),
        });
        Ok(frame)
    }
}

fn read(path: &std::path::Path, memory_limit: u64) -> Result<Image, StudioError> {
    let limits = Limits {
        max_bytes: memory_limit,
    };
    Ok(aureole_io::read::read_image(path, limits)?.image)
}
