//! `aureole studio`: the local web studio, served from this binary.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;

use anyhow::anyhow;
use aureole_io::limits::default_memory_limit;
use aureole_studio::{Access, Roots, Studio};

use crate::device::DeviceArg;
use crate::Failure;

#[derive(clap::Args)]
#[command(
    after_help = "The page, its script and style are in this binary: nothing is fetched from \
the network. Files are read only under the --root folders (default: the folders of the IMAGE \
arguments, else the current folder); a path outside them is refused. Only the address printed at \
start, with its secret token, opens the studio: scripts send the token as `Authorization: Bearer \
TOKEN` or `?token=TOKEN`; pages of other sites and other host names are refused."
)]
pub struct Args {
    /// Images to offer first (their folders become roots).
    #[arg(value_name = "IMAGE")]
    images: Vec<PathBuf>,

    /// A folder the studio may read images from (repeatable).
    #[arg(long, value_name = "DIR")]
    root: Vec<PathBuf>,

    /// The port (default: a free one).
    #[arg(long, default_value = "0")]
    port: u16,

    /// The address to listen on. Default 127.0.0.1: only this machine can
    /// reach the studio. Another address lets the network read your images.
    #[arg(long, value_name = "ADDR")]
    listen: Option<IpAddr>,

    /// Do not open the page in the default browser.
    #[arg(long)]
    no_browser: bool,

    /// Where previews and exports convolve: auto takes a hardware GPU
    /// when there is one, gpu insists (a software adapter too), cpu never
    /// looks.
    #[arg(long, value_enum, default_value_t = DeviceArg::Auto)]
    device: DeviceArg,
}

pub fn run(args: &Args, quiet: bool) -> Result<(), Failure> {
    let mut folders = args.root.clone();
    if folders.is_empty() {
        folders = args
            .images
            .iter()
            .map(|image| aureole_io::atomic::folder_of(image).to_path_buf())
            .collect();
    }
    if folders.is_empty() {
        folders.push(PathBuf::from("."));
    }
    let roots = Roots::new(&folders).map_err(|e| Failure::Usage(anyhow!("{e}")))?;
    let address = args.listen.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST));
    if !address.is_loopback() {
        say!(
            "aureole: warning: listening on {address}: other machines can reach the studio and read the images under its folders"
        );
    }
    // The first image opens first, named as the studio names it.
    let first = match args.images.first() {
        Some(image) => {
            let absolute = image
                .canonicalize()
                .map_err(|e| Failure::Usage(anyhow!("{}: {e}", image.display())))?;
            Some(
                roots
                    .resolve(&absolute.display().to_string())
                    .map_err(|e| Failure::Usage(anyhow!("{e}")))?,
            )
        }
        None => None,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| Failure::Run(anyhow!("cannot start the server: {e}")))?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind(SocketAddr::new(address, args.port))
            .await
            .map_err(|e| Failure::Run(anyhow!("cannot listen on {address}:{}: {e}", args.port)))?;
        let bound = listener
            .local_addr()
            .map_err(|e| Failure::Run(anyhow!("{e}")))?;
        let access = Access::new(bound)
            .map_err(|e| Failure::Run(anyhow!("cannot start the studio: {e}")))?;
        let opened = |mut url: String| {
            if let Some(first) = &first {
                url.push_str("&image=");
                url.push_str(&query_escaped(&first.display().to_string()));
            }
            url
        };
        let url = opened(access.url(bound));
        let others: Vec<String> = access.urls(bound).into_iter().skip(1).map(opened).collect();
        let studio = Studio::new(roots, default_memory_limit(), args.device.into(), access);
        // The URL goes to stdout so that a script can read it.
        say!(stdout: "{url}");
        if !quiet {
            say!("aureole: studio at {url} (Ctrl-C stops it)");
            for other in &others {
                say!("aureole: also at {other}");
            }
        }
        if !args.no_browser {
            open_browser(&url, quiet);
        }
        aureole_studio::serve(listener, studio)
            .await
            .map_err(|e| Failure::Run(anyhow!("the server stopped: {e}")))
    })
}

/// `text` as a URL query value: unreserved characters kept, the rest
/// percent-encoded byte by byte.
fn query_escaped(text: &str) -> String {
    text.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' | b'/' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// Opens `url` with the desktop's opener; without one, the URL printed is
/// the way in.
fn open_browser(url: &str, quiet: bool) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    let spawned = std::process::Command::new(opener)
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn();
    if spawned.is_err() && !quiet {
        say!("aureole: note: cannot open a browser ({opener}); open {url}");
    }
}
