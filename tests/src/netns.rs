//! Hosts on one machine for the multi-host tests: Linux network namespaces joined by veth
//! pairs to a switch (a Linux bridge in a namespace of its own), so that the hosts' bridges
//! reach each other only over a network the test controls.
//!
//! - [`Net::create`] makes the switch and `n` hosts, host `i` at `10.77.0.<i + 1>/24`; it
//!   fails (the test then skips and says why) where the kernel or the user may not create
//!   namespaces.
//! - [`Net::set_loss`] drops a share of the packets each host receives (nftables `numgen
//!   random` on the input hook: one chance per packet and link direction).
//! - [`Net::cut`] takes a host's switch port down (a partition) and up again.
//!
//! Everything is removed on drop. Only addresses inside the namespaces are used.

use std::process::Command;

/// The namespaces of one test.
pub struct Net {
    switch: String,
    hosts: Vec<String>,
}

/// Runs `ip ARGS`; `Err` with its words on failure.
fn ip(args: &[&str]) -> Result<(), String> {
    run("ip", args, None)
}

fn run(program: &str, args: &[&str], stdin: Option<&str>) -> Result<(), String> {
    use std::io::Write;
    let mut cmd = Command::new(program);
    cmd.args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("cannot run {program}: {e}"))?;
    if let (Some(text), Some(mut input)) = (stdin, child.stdin.take()) {
        input
            .write_all(text.as_bytes())
            .map_err(|e| format!("{program}: {e}"))?;
    }
    let out = child
        .wait_with_output()
        .map_err(|e| format!("{program}: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{program} {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

impl Net {
    /// A switch and `n` hosts for test `tag` (a few letters: namespace names carry it and
    /// this process's id).
    pub fn create(tag: &str, n: usize) -> Result<Net, String> {
        let base = format!("hn{}{tag}", std::process::id() % 100_000);
        let net = Net {
            switch: format!("{base}-sw"),
            hosts: (0..n).map(|i| format!("{base}-h{i}")).collect(),
        };
        // Created one by one; what exists is removed on drop, whatever failed.
        ip(&["netns", "add", &net.switch])?;
        let sw = net.switch.as_str();
        ip(&["-n", sw, "link", "add", "br0", "type", "bridge"])?;
        ip(&["-n", sw, "link", "set", "br0", "up"])?;
        for (i, ns) in net.hosts.iter().enumerate() {
            ip(&["netns", "add", ns])?;
            let port = format!("p{i}");
            ip(&[
                "link", "add", "eth0", "netns", ns, "type", "veth", "peer", "name", &port, "netns",
                sw,
            ])?;
            let addr = format!("{}/24", Self::addr(i));
            ip(&["-n", ns, "addr", "add", &addr, "dev", "eth0"])?;
            ip(&["-n", ns, "link", "set", "eth0", "up"])?;
            ip(&["-n", ns, "link", "set", "lo", "up"])?;
            ip(&["-n", sw, "link", "set", &port, "master", "br0"])?;
            ip(&["-n", sw, "link", "set", &port, "up"])?;
        }
        Ok(net)
    }

    /// Host `i`'s namespace.
    pub fn ns(&self, i: usize) -> &str {
        &self.hosts[i]
    }

    /// Host `i`'s address.
    pub fn addr(i: usize) -> String {
        format!("10.77.0.{}", i + 1)
    }

    /// `Ok` when [`Net::set_loss`] can work here: `nft` (Debian's nftables) is installed. The
    /// README's test command does not ask for it, so a test that needs it skips without it.
    pub fn loss_tool() -> Result<(), String> {
        match Command::new("nft").arg("--version").output() {
            Ok(out) if out.status.success() => Ok(()),
            Ok(out) => Err(format!("`nft --version` failed: {}", out.status)),
            Err(e) => Err(format!("nftables (`nft`) is not installed here ({e})")),
        }
    }

    /// Drops `percent` % of the packets every host receives, at random (nftables).
    pub fn set_loss(&self, percent: u32) -> Result<(), String> {
        let rules = format!(
            "table inet hnavloss {{\n  chain input {{\n    type filter hook input priority 0; \
             policy accept;\n    numgen random mod 100 < {percent} drop\n  }}\n}}\n"
        );
        for ns in &self.hosts {
            run("ip", &["netns", "exec", ns, "nft", "-f", "-"], Some(&rules))?;
        }
        Ok(())
    }

    /// Takes host `i`'s link down (`up` false: a partition) or up again.
    pub fn cut(&self, i: usize, up: bool) -> Result<(), String> {
        let port = format!("p{i}");
        let state = if up { "up" } else { "down" };
        ip(&["-n", &self.switch, "link", "set", &port, state])
    }
}

impl Drop for Net {
    fn drop(&mut self) {
        // Deleting a namespace deletes its ends of the veth pairs, and with them the peers.
        for ns in self.hosts.iter().chain(std::iter::once(&self.switch)) {
            let _ = ip(&["netns", "del", ns]);
        }
    }
}
