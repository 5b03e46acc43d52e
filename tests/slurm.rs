//! A real Slurm run (issue 15): a one-node cluster on this machine (munged, slurmctld, slurmd on 127.0.0.1, a
//! minimal slurm.conf in a temporary directory), scripts/slurm/render-array.sh submitting a 4-task array of a small
//! render and the dependent merge job; the merged image must match a single-run render within 1e-5 relative.
//!
//! Ignored by default (it needs root and Debian's `slurm-wlm` and `munge`); `.ci/run` installs them and runs
//! `cargo test --release --test slurm -- --ignored`. If Slurm cannot be started the test FAILS, saying why.

use mislab::state::RenderState;
use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_mislab");
const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/slurm/render-array.sh");

/// The daemons, stopped (SIGKILL by process id, then reaped) when the test ends, however it ends.
struct Cluster {
    dir: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for (_, c) in self.daemons.iter_mut().rev() {
            let _ = c.kill();
            let _ = c.wait();
        }
        // The daemons' logs and the parts stay where a failing test can be looked into.
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

impl Cluster {
    fn log_tails(&self) -> String {
        let mut out = String::new();
        for f in ["munged.log", "slurmctld.log", "slurmd.log"] {
            let t = std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
            let lines: Vec<&str> = t.lines().collect();
            out += &format!("--- {f} (last lines)\n{}\n", lines[lines.len().saturating_sub(15)..].join("\n"));
        }
        out
    }

    fn slurm(&self, cmd: &str, args: &[&str]) -> String {
        let o = Command::new(cmd)
            .args(args)
            .env("SLURM_CONF", self.dir.join("slurm.conf"))
            .output()
            .unwrap_or_else(|e| panic!("{cmd}: {e}"));
        format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
    }
}

fn need(tool: &str) -> String {
    for dir in ["/usr/sbin", "/usr/bin", "/sbin", "/bin"] {
        let p = Path::new(dir).join(tool);
        if p.exists() {
            return p.display().to_string();
        }
    }
    panic!("the Slurm test needs `{tool}`: apt-get install slurm-wlm munge (Debian 12: Slurm 22.05), or run .ci/run");
}

fn spawn(cluster: &mut Cluster, name: &'static str, cmd: &str, args: &[&str]) {
    let log = std::fs::File::create(cluster.dir.join(format!("{name}.out"))).unwrap();
    let child = Command::new(cmd)
        .args(args)
        .env("SLURM_CONF", cluster.dir.join("slurm.conf"))
        .stdout(log.try_clone().unwrap())
        .stderr(log)
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
    cluster.daemons.push((name, child));
}

fn start_cluster() -> Cluster {
    let (munged, mungekey, ctld, slurmd) = (need("munged"), need("mungekey"), need("slurmctld"), need("slurmd"));
    need("sbatch");
    assert!(
        String::from_utf8_lossy(&Command::new("id").arg("-u").output().unwrap().stdout).trim() == "0",
        "the Slurm test starts slurmd, which launches jobs as their user: run it as root (CI does)"
    );
    let dir = std::env::temp_dir().join(format!("mislab-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for d in ["spool", "state"] {
        std::fs::create_dir_all(dir.join(d)).unwrap();
    }
    let host = String::from_utf8(Command::new("hostname").arg("-s").output().unwrap().stdout).unwrap();
    let host = host.trim();
    let port = 20000 + (std::process::id() % 20000) as u16 * 2;
    let d = dir.display();
    let conf = format!(
        "ClusterName=mislabci\nSlurmctldHost={host}(127.0.0.1)\nSlurmctldPort={port}\nSlurmdPort={}\n\
         AuthType=auth/munge\nAuthInfo=socket={d}/munge.sock\nCredType=cred/munge\nMpiDefault=none\n\
         ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nReturnToService=2\nSlurmUser=root\nSlurmdUser=root\n\
         SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\nSlurmdSpoolDir={d}/spool\n\
         StateSaveLocation={d}/state\nSchedulerType=sched/backfill\nSelectType=select/cons_tres\n\
         SelectTypeParameters=CR_Core\nJobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
         SlurmctldLogFile={d}/slurmctld.log\nSlurmdLogFile={d}/slurmd.log\nMinJobAge=600\n\
         NodeName={host} NodeAddr=127.0.0.1 CPUs=2 RealMemory=1000 State=UNKNOWN\n\
         PartitionName=ci Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
        port + 1
    );
    std::fs::write(dir.join("slurm.conf"), conf).unwrap();
    let key = dir.join("munge.key");
    let ok = Command::new(&mungekey).arg("-c").arg("-k").arg(&key).status().unwrap().success();
    assert!(ok, "mungekey could not create {}", key.display());
    let mut cluster = Cluster { dir: dir.clone(), daemons: Vec::new() };
    let s = |p: &str| format!("{d}/{p}");
    spawn(
        &mut cluster,
        "munged",
        &munged,
        &[
            "-F",
            "-f",
            &format!("--socket={}", s("munge.sock")),
            &format!("--key-file={}", key.display()),
            &format!("--pid-file={}", s("munged.pid")),
            &format!("--log-file={}", s("munged.log")),
            &format!("--seed-file={}", s("munge.seed")),
        ],
    );
    std::thread::sleep(Duration::from_millis(300));
    let conf = s("slurm.conf");
    spawn(&mut cluster, "slurmctld", &ctld, &["-D", "-f", &conf]);
    spawn(&mut cluster, "slurmd", &slurmd, &["-D", "-f", &conf]);
    // Wait for the node to come up idle.
    let t0 = Instant::now();
    loop {
        let exited = cluster.daemons.iter_mut().find_map(|(name, c)| c.try_wait().ok().flatten().map(|st| (*name, st)));
        if let Some((name, status)) = exited {
            let out = std::fs::read_to_string(dir.join(format!("{name}.out"))).unwrap_or_default();
            panic!("{name} exited at start-up ({status}):\n{out}\n{}", cluster.log_tails());
        }
        let state = cluster.slurm("sinfo", &["-h", "-o", "%T"]);
        if state.trim() == "idle" {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(40),
            "the one-node cluster did not come up within 40 s (sinfo: {state})\n{}",
            cluster.log_tails()
        );
        std::thread::sleep(Duration::from_millis(300));
    }
    eprintln!("slurm: one-node cluster up in {:.1} s", t0.elapsed().as_secs_f64());
    cluster
}

fn job_state(cluster: &Cluster, id: &str) -> String {
    let o = cluster.slurm("scontrol", &["show", "job", "-o", id]);
    let field = |k: &str| o.split_whitespace().find_map(|w| w.strip_prefix(k)).unwrap_or("?").to_string();
    format!("{} {}", field("JobState="), field("Reason="))
}

#[test]
#[ignore = "needs root, slurm-wlm and munge: run by .ci/run with --ignored"]
fn slurm_job_array_of_four_parts_and_merge_matches_a_single_render() {
    let t_all = Instant::now();
    let cluster = start_cluster();
    let out = cluster.dir.join("parts");
    let render = ["veach-mis", "--width", "64", "--height", "48", "--spp", "40"];
    let o = Command::new("bash")
        .arg(SCRIPT)
        .args(["-n", "4", "-c", "1", "-m", BIN, "-d"])
        .arg(&out)
        .arg("--")
        .args(render)
        .env("SLURM_CONF", cluster.dir.join("slurm.conf"))
        .output()
        .unwrap();
    let printed = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "render-array.sh failed: {printed}{}\n{}",
        String::from_utf8_lossy(&o.stderr),
        cluster.log_tails()
    );
    let ids: Vec<&str> = printed.split_whitespace().collect();
    assert_eq!(ids.len(), 2, "render-array.sh should print the array's and the merge's job ids: {printed}");
    // The single-run render meanwhile (same settings, same seed).
    let single = cluster.dir.join("single.state");
    let s = Command::new(BIN)
        .arg("render")
        .args(render)
        .arg("-o")
        .arg(cluster.dir.join("single.exr"))
        .arg("--state")
        .arg(&single)
        .output()
        .unwrap();
    assert!(s.status.success(), "single render failed: {}", String::from_utf8_lossy(&s.stderr));
    let t0 = Instant::now();
    let logs = || {
        let mut t = String::new();
        for f in ["part-0.log", "part-1.log", "part-2.log", "part-3.log", "merge.log"] {
            t += &format!("--- {f}\n{}\n", std::fs::read_to_string(out.join(f)).unwrap_or_default());
        }
        t
    };
    loop {
        let st = job_state(&cluster, ids[1]);
        if st.starts_with("COMPLETED") {
            break;
        }
        let failed = ["FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "BOOT_FAIL"];
        assert!(
            !failed.iter().any(|f| st.starts_with(f)) && !st.contains("DependencyNeverSatisfied"),
            "the merge job {} ended {st}; array {}: {}\n{}{}",
            ids[1],
            ids[0],
            cluster.slurm("squeue", &["-h"]),
            logs(),
            cluster.log_tails()
        );
        assert!(
            t0.elapsed() < Duration::from_secs(150),
            "the jobs did not finish within 150 s (merge job: {st})\n{}{}",
            logs(),
            cluster.log_tails()
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    eprintln!("slurm: 4-task array + merge done in {:.1} s", t0.elapsed().as_secs_f64());
    for k in 0..4 {
        let st = job_state(&cluster, &format!("{}_{k}", ids[0]));
        assert!(st.starts_with("COMPLETED"), "array task {k}: {st}\n{}", logs());
    }
    let merged = RenderState::read(&out.join("merged.state")).unwrap_or_else(|e| panic!("{e}\n{}", logs()));
    assert!(out.join("merged.exr").exists(), "no merged.exr\n{}", logs());
    let single = RenderState::read(&single).unwrap();
    assert_eq!(merged.header.range, (0, 40));
    let mut worst = 0f64;
    for (a, b) in single.accum.iter().zip(&merged.accum) {
        assert_eq!((a.count, a.nonfinite), (b.count, b.nonfinite));
        for c in 0..3 {
            let (x, y) = (a.mean[c] as f64, b.mean[c] as f64);
            if x != y {
                worst = worst.max((x - y).abs() / x.abs().max(y.abs()));
            }
        }
    }
    assert!(worst <= 1e-5, "merged Slurm parts differ from the single render by {worst:e} relative");
    eprintln!(
        "slurm: merged image matches the single render (worst relative difference {worst:e}); {:.1} s in all",
        t_all.elapsed().as_secs_f64()
    );
    drop(cluster);
}
