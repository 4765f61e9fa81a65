//! The other Box2D build in a child process.
//!
//! boxdd-sys compiles Box2D's C once per build, SSE2 by default or AVX2 with its `simd-avx2`
//! feature, and both export the same C symbols, so one binary holds one of them. To still time
//! both in one run, chunk by chunk in turn with the other engines, the parent starts the other
//! build of this tool as `vs-peers --serve SCENE` and talks to it over stdin/stdout, one line per
//! request:
//!
//! - the child answers `ready LABEL` once the scene is built;
//! - `warm N`: N untimed steps, answer `ok`;
//! - `run N`: N steps each timed in the child with `Instant`, answer `ALLOCS MS MS ...`;
//! - `sanity`: answer `TOP MEAN AWAKE LOST`; `contacts`: answer the count;
//! - `quit` or end of input: exit.
//!
//! While the child steps, the parent blocks on the pipe and uses no CPU, so each chunk is timed
//! as if the engine were in the parent; the pipe round trip is outside the timed steps.

use crate::{box2d, Engine, Sanity};
use std::cell::RefCell;
use std::io::{self, BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// Where the README's build command puts the other build (relative to this crate).
pub const DEFAULT_OTHER_BINARY: &str = if cfg!(feature = "avx2") {
    "target/release/vs-peers"
} else {
    "target/avx2/vs-peers"
};

/// The other build's path under this crate's directory, if it has been built.
pub fn default_other_binary() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_OTHER_BINARY);
    p.is_file().then_some(p)
}

/// How the tables name the other build.
pub fn other_label() -> &'static str {
    if cfg!(feature = "avx2") {
        "Box2D v3 (SSE2)"
    } else {
        "Box2D v3 (AVX2)"
    }
}

/// The set-up called `name`: a benchmark scene, `pyramid-BASE` (the largest-pyramid probe) or
/// `pile_N` (the growth scene).
fn setup_named(name: &str) -> Option<tiltbox::measure::cases::Setup> {
    if let Some(base) = name.strip_prefix("pyramid-") {
        return base.parse().ok().map(crate::pyramid_setup);
    }
    if let Some(boxes) = name.strip_prefix("pile_") {
        return boxes.parse().ok().map(crate::pile_setup);
    }
    tiltbox::measure::cases::benchmark_setups()
        .into_iter()
        .find(|s| s.name == name)
}

/// The child's side: build `scene` in this build's Box2D and answer requests until told to quit.
pub fn serve(scene: &str) {
    let Some(setup) = setup_named(scene) else {
        eprintln!("--serve: no scene called {scene}");
        std::process::exit(2);
    };
    let mut engine = box2d::Box2d::new(&setup);
    let stdout = io::stdout();
    let mut out = stdout.lock();
    let answer = |out: &mut io::StdoutLock, s: String| {
        writeln!(out, "{s}").and_then(|_| out.flush()).is_ok()
    };
    if !answer(&mut out, format!("ready {}", box2d::LABEL)) {
        return;
    }
    let mut ms = Vec::new();
    for line in io::stdin().lock().lines() {
        let Ok(line) = line else { return };
        let mut words = line.split_whitespace();
        let reply = match (
            words.next(),
            words.next().and_then(|n| n.parse::<usize>().ok()),
        ) {
            (Some("warm"), Some(n)) => {
                engine.warm(n);
                "ok".to_string()
            }
            (Some("run"), Some(n)) => {
                ms.clear();
                let allocs = engine.run_timed(n, &mut ms);
                let mut s = allocs.to_string();
                for t in &ms {
                    s += &format!(" {t:e}");
                }
                s
            }
            (Some("sanity"), _) => {
                let s = engine.sanity();
                format!(
                    "{} {} {} {} {}",
                    s.top_y, s.mean_y, s.awake, s.lost, s.joint_gap
                )
            }
            (Some("contacts"), _) => engine.contact_pairs().to_string(),
            _ => return,
        };
        if !answer(&mut out, reply) {
            return;
        }
    }
}

/// The parent's side: an `Engine` whose steps run in the child.
pub struct Remote {
    child: Child,
    /// The pipes; in a cell because even the `&self` queries (sanity, contacts) write a request.
    pipes: RefCell<(ChildStdin, BufReader<ChildStdout>)>,
}

impl Remote {
    /// Start `binary --serve scene` and wait until the scene is built.
    pub fn spawn(binary: &Path, scene: &str) -> io::Result<Remote> {
        let mut child = Command::new(binary)
            .arg("--workers")
            .arg(crate::workers().to_string())
            .arg("--serve")
            .arg(scene)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
        let r = Remote {
            child,
            pipes: RefCell::new((stdin, stdout)),
        };
        let hello = read_line(&mut r.pipes.borrow_mut().1)?;
        match hello.strip_prefix("ready ") {
            Some(label) if label == other_label() => Ok(r),
            _ => Err(io::Error::other(format!(
                "{} answered {hello:?}, expected \"ready {}\"",
                binary.display(),
                other_label()
            ))),
        }
    }

    fn ask(&self, request: &str) -> String {
        let mut pipes = self.pipes.borrow_mut();
        let (stdin, stdout) = &mut *pipes;
        writeln!(stdin, "{request}")
            .and_then(|_| stdin.flush())
            .and_then(|_| read_line(stdout))
            .unwrap_or_else(|e| panic!("the other Box2D build failed on {request:?}: {e}"))
    }
}

fn read_line(from: &mut BufReader<ChildStdout>) -> io::Result<String> {
    let mut s = String::new();
    if from.read_line(&mut s)? == 0 {
        return Err(io::Error::other("the child process closed its output"));
    }
    Ok(s.trim_end().to_string())
}

impl Drop for Remote {
    fn drop(&mut self) {
        {
            let stdin = &mut self.pipes.get_mut().0;
            let _ = writeln!(stdin, "quit").and_then(|_| stdin.flush());
        }
        let _ = self.child.wait();
    }
}

impl Engine for Remote {
    fn step(&mut self) {
        self.ask("warm 1");
    }
    fn warm(&mut self, n: usize) {
        self.ask(&format!("warm {n}"));
    }
    fn run_timed(&mut self, n: usize, ms: &mut Vec<f64>) -> usize {
        let reply = self.ask(&format!("run {n}"));
        let mut words = reply.split_whitespace();
        let allocs = words.next().and_then(|w| w.parse().ok()).unwrap_or(0);
        ms.extend(words.filter_map(|w| w.parse::<f64>().ok()));
        allocs
    }
    fn sanity(&self) -> Sanity {
        let reply = self.ask("sanity");
        let w: Vec<&str> = reply.split_whitespace().collect();
        let f = |i: usize| {
            w.get(i)
                .and_then(|x| x.parse::<f32>().ok())
                .unwrap_or(f32::NAN)
        };
        let u = |i: usize| w.get(i).and_then(|x| x.parse::<usize>().ok()).unwrap_or(0);
        Sanity {
            top_y: f(0),
            mean_y: f(1),
            awake: u(2),
            lost: u(3),
            joint_gap: f(4),
        }
    }
    fn contact_pairs(&self) -> usize {
        self.ask("contacts").parse().unwrap_or(0)
    }
    fn dynamic_bodies(&self) -> Vec<crate::BodyState> {
        // Checked in the SSE2 build: the same code, compiled for other SIMD.
        Vec::new()
    }
    fn max_penetration(&self) -> f64 {
        f64::NAN
    }
}
