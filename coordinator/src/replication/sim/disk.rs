//! The simulated disk ([`SimDisk`]): the journal's files are real files in the run's scratch
//! directory (the consensus-log reader reads them back with `std::fs`, as a restarted process
//! does), but every write goes through a [`Disk`] that knows what an `fdatasync` made durable
//! and fails an operation when the nemesis armed it to.
//!
//! The model, per file: what was synced is durable; what was written since is in the page
//! cache only. A process that is killed leaves the page cache as it was (the next
//! incarnation reads it all). A power loss keeps the durable bytes and, of the writes since
//! the last sync, the first `j` (any `j`, the last one kept torn: a prefix of it, or as many
//! zero bytes); the rest is gone. A failed write writes a prefix of its bytes and reports
//! the error. A failed fsync reports the error and drops the unsynced writes (the kernel has
//! dropped its dirty pages); the process, which cannot know what is on the disk, exits. Not
//! modelled: a page that stays in the cache after a failed fsync while the disk holds the
//! old one (reads would then see data a later power loss takes), and the loss of directory
//! entries (a segment created and synced is there after a crash).

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use hnav_runtime::durable::{Disk, DiskFile, RealDisk};

use super::rng::Rng;

/// A fault the nemesis arms on a replica's disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiskFault {
    /// A write fails after writing a prefix of its bytes.
    FailWrite,
    /// An fsync fails; the writes since the last one are lost.
    FailFsync,
    /// The power fails during a write, which is torn.
    Torn,
}

impl DiskFault {
    /// Its name in a trace.
    pub fn name(self) -> &'static str {
        match self {
            DiskFault::FailWrite => "fail-write",
            DiskFault::FailFsync => "fail-fsync",
            DiskFault::Torn => "torn",
        }
    }

    /// The fault named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [DiskFault::FailWrite, DiskFault::FailFsync, DiskFault::Torn]
            .into_iter()
            .find(|f| f.name() == name)
    }
}

/// What a fault did, once it fired: what the crash that follows must do to the files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fired {
    /// A write failed (its prefix is cut off again by the writer, or stays as a torn tail).
    Write,
    /// An fsync failed: the unsynced writes are to be dropped.
    Fsync,
    /// The power failed: the files are to be cut back to what a power loss leaves.
    Power,
}

#[derive(Debug)]
enum Pending {
    Write(u64, Vec<u8>),
    SetLen(u64),
}

/// A file as the disk holds it durably, and the writes since its last sync.
#[derive(Debug, Default)]
struct Image {
    durable: Vec<u8>,
    pending: Vec<Pending>,
}

impl Image {
    fn apply(content: &mut Vec<u8>, op: &Pending) {
        match op {
            Pending::Write(offset, bytes) => {
                let (at, end) = (*offset as usize, *offset as usize + bytes.len());
                if content.len() < end {
                    content.resize(end, 0);
                }
                content[at..end].copy_from_slice(bytes);
            }
            Pending::SetLen(len) => content.resize(*len as usize, 0),
        }
    }

    fn sync(&mut self) {
        for op in std::mem::take(&mut self.pending) {
            Self::apply(&mut self.durable, &op);
        }
    }
}

#[derive(Debug)]
struct Armed {
    fault: DiskFault,
    /// Operations of its kind (writes, or fsyncs) to let pass first.
    skip: u32,
}

/// One replica's disk, across its incarnations.
#[derive(Debug)]
struct State {
    files: BTreeMap<PathBuf, Image>,
    armed: Option<Armed>,
    fired: Option<Fired>,
    /// Sabotage for the checker's own test: fsyncs report success and make nothing durable.
    lying: bool,
    rng: Rng,
    faults: u64,
}

/// A replica's simulated disk (how it fails: the top of its file). Clones share the disk; each
/// incarnation of the replica writes through its own [`SimDisk::incarnation`], which dies
/// with it.
#[derive(Clone, Debug)]
pub struct SimDisk {
    state: Rc<RefCell<State>>,
    alive: Rc<Cell<bool>>,
}

fn gone() -> io::Error {
    io::Error::other("the process is gone (simulated crash)")
}

fn injected(what: &str) -> io::Error {
    io::Error::other(format!("simulated {what} failure (nemesis)"))
}

impl SimDisk {
    /// A disk with no files, drawing tears from `rng`; with `lying`, its fsyncs make nothing
    /// durable.
    pub fn new(rng: Rng, lying: bool) -> Self {
        SimDisk {
            state: Rc::new(RefCell::new(State {
                files: BTreeMap::new(),
                armed: None,
                fired: None,
                lying,
                rng,
                faults: 0,
            })),
            alive: Rc::new(Cell::new(false)),
        }
    }

    /// The handle a new incarnation writes through; the previous one's is dead.
    pub fn incarnation(&self) -> SimDisk {
        self.alive.set(false);
        let next = SimDisk {
            state: Rc::clone(&self.state),
            alive: Rc::new(Cell::new(true)),
        };
        next.state.borrow_mut().fired = None;
        next
    }

    /// Arms `fault` to fire at the `nth` (from 1) write, or fsync for
    /// [`DiskFault::FailFsync`], from now on.
    pub fn arm(&self, fault: DiskFault, nth: u32) {
        self.state.borrow_mut().armed = Some(Armed {
            fault,
            skip: nth.saturating_sub(1),
        });
    }

    /// Disarms a fault that has not fired.
    pub fn disarm(&self) {
        self.state.borrow_mut().armed = None;
    }

    /// The fault that fired since the incarnation began, if one did.
    pub fn fired(&self) -> Option<Fired> {
        self.state.borrow().fired
    }

    /// Faults fired so far.
    pub fn faults(&self) -> u64 {
        self.state.borrow().faults
    }

    /// The incarnation is over (its process killed): every later operation of its handle
    /// fails, so that nothing it still holds (a writer's sync on drop) reaches the disk.
    pub fn kill(&self) {
        self.alive.set(false);
    }

    /// The crash after a fault, or a power loss: the files are cut back as `Fired` says
    /// (nothing for a failed write, whose writer cut it back itself or left a torn tail).
    pub fn crash(&self, how: Option<Fired>) -> io::Result<()> {
        self.kill();
        let mut st = self.state.borrow_mut();
        let State { files, rng, .. } = &mut *st;
        for (path, image) in files.iter_mut() {
            let content = match how {
                Some(Fired::Fsync) => image.durable.clone(),
                Some(Fired::Power) => power_loss(image, rng),
                Some(Fired::Write) | None => continue,
            };
            std::fs::write(path, &content)?;
            image.durable = content;
            image.pending.clear();
        }
        Ok(())
    }

    fn check(&self) -> io::Result<()> {
        if self.alive.get() {
            Ok(())
        } else {
            Err(gone())
        }
    }

    fn file(&self, path: &Path, file: File) -> SimFile {
        SimFile {
            file,
            path: path.to_path_buf(),
            disk: self.clone(),
        }
    }
}

/// What a power loss leaves of `image`: the durable bytes, then the first `j` unsynced
/// writes, the last of them torn.
fn power_loss(image: &Image, rng: &mut Rng) -> Vec<u8> {
    let mut content = image.durable.clone();
    let kept = rng.range(0, image.pending.len() as u64 + 1) as usize;
    for (i, op) in image.pending[..kept].iter().enumerate() {
        match op {
            Pending::Write(offset, bytes) if i + 1 == kept => {
                let k = rng.range(0, bytes.len() as u64) as usize;
                let torn = if rng.chance(50) {
                    bytes[..k].to_vec()
                } else {
                    vec![0; k]
                };
                Image::apply(&mut content, &Pending::Write(*offset, torn));
            }
            op => Image::apply(&mut content, op),
        }
    }
    content
}

impl State {
    /// Whether the armed fault fires at this operation (a write, or an fsync).
    fn fires(&mut self, fsync: bool) -> Option<DiskFault> {
        let armed = self.armed.as_mut()?;
        if (armed.fault == DiskFault::FailFsync) != fsync {
            return None;
        }
        if armed.skip > 0 {
            armed.skip -= 1;
            return None;
        }
        let fault = armed.fault;
        self.armed = None;
        self.faults += 1;
        Some(fault)
    }
}

impl Disk for SimDisk {
    type File = SimFile;

    fn create_new(&self, path: &Path) -> io::Result<SimFile> {
        self.check()?;
        let file = RealDisk.create_new(path)?;
        self.state
            .borrow_mut()
            .files
            .insert(path.to_path_buf(), Image::default());
        Ok(self.file(path, file))
    }

    fn open_or_create(&self, path: &Path) -> io::Result<SimFile> {
        self.check()?;
        let file = RealDisk.open_or_create(path)?;
        let mut st = self.state.borrow_mut();
        if !st.files.contains_key(path) {
            // A file this disk has not written: what is there is durable.
            let durable = std::fs::read(path)?;
            st.files.insert(
                path.to_path_buf(),
                Image {
                    durable,
                    pending: Vec::new(),
                },
            );
        }
        drop(st);
        Ok(self.file(path, file))
    }

    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        self.check()?;
        RealDisk.rename(from, to)?;
        let mut st = self.state.borrow_mut();
        if let Some(image) = st.files.remove(from) {
            st.files.insert(to.to_path_buf(), image);
        }
        Ok(())
    }

    fn remove_file(&self, path: &Path) -> io::Result<()> {
        self.check()?;
        RealDisk.remove_file(path)?;
        self.state.borrow_mut().files.remove(path);
        Ok(())
    }

    fn sync_dir(&self, _: &Path) -> io::Result<()> {
        self.check()
    }
}

/// A file of a [`SimDisk`].
#[derive(Debug)]
pub struct SimFile {
    file: File,
    path: PathBuf,
    disk: SimDisk,
}

impl SimFile {
    fn pending(&self, op: Pending) {
        let mut st = self.disk.state.borrow_mut();
        if let Some(image) = st.files.get_mut(&self.path) {
            image.pending.push(op);
        }
    }
}

impl DiskFile for SimFile {
    fn write_at(&self, offset: u64, bytes: &[u8]) -> io::Result<()> {
        self.disk.check()?;
        let fault = self.disk.state.borrow_mut().fires(false);
        let Some(fault) = fault else {
            self.file.write_all_at(bytes, offset)?;
            self.pending(Pending::Write(offset, bytes.to_vec()));
            return Ok(());
        };
        let k = self
            .disk
            .state
            .borrow_mut()
            .rng
            .range(0, bytes.len() as u64) as usize;
        self.file.write_all_at(&bytes[..k], offset)?;
        self.pending(Pending::Write(offset, bytes[..k].to_vec()));
        let fired = match fault {
            DiskFault::Torn => {
                self.disk.alive.set(false);
                Fired::Power
            }
            _ => Fired::Write,
        };
        self.disk.state.borrow_mut().fired = Some(fired);
        Err(injected("write"))
    }

    fn set_len(&self, len: u64) -> io::Result<()> {
        self.disk.check()?;
        self.file.set_len(len)?;
        self.pending(Pending::SetLen(len));
        Ok(())
    }

    fn sync_data(&self) -> io::Result<()> {
        self.disk.check()?;
        let mut st = self.disk.state.borrow_mut();
        if st.fires(true).is_some() {
            st.fired = Some(Fired::Fsync);
            return Err(injected("fsync"));
        }
        if !st.lying {
            if let Some(image) = st.files.get_mut(&self.path) {
                image.sync();
            }
        }
        Ok(())
    }

    fn size(&self) -> io::Result<u64> {
        Ok(self.file.metadata()?.len())
    }
}
