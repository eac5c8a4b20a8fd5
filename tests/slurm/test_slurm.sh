#!/usr/bin/env bash
# The Slurm path on a real Slurm: a private single-node cluster (every file in one temporary folder,
# no authentication, 127.0.0.1 and free ports only; see ../shared/SLURM.md) is started, used and
# stopped here. The Delft block as 4 shards (a job array plus a merge job, scripts/slurm/city3d-slurm)
# gives exactly the output of one process (CityJSON, CityJSONSeq, GeoPackage and models byte for byte,
# the reports and report.html up to their timings); then one task is killed (kill -9 in the middle of its
# shard), the merge does not run, and `city3d-slurm resubmit` reruns only that shard, which resumes
# from its journal: the output is still identical.
# Usage: test_slurm.sh CITY3D REPOSITORY SHARED_DATA. Exit 77: skipped (no Slurm or no data).
set -euo pipefail
city3d="$1" repo="$2" data="$3/ahn3_delft"
skip() { echo "SKIP: $*"; exit 77; }
[[ -x /usr/sbin/slurmctld && -x /usr/sbin/slurmd ]] && command -v sbatch > /dev/null ||
  skip "Slurm is not installed (scripts/setup.sh test installs slurmctld slurmd slurm-client)"
[[ -f "$data/ahn3_cropped_1.las" ]] || skip "../shared/data is not beside the repository"

tmp="$(mktemp -d /tmp/city3d-slurm-test.XXXXXX)"
cluster="$tmp/cluster"
mkdir -p "$cluster/state" "$cluster/spool"
stop_cluster() {
  local f pid
  for f in "$cluster/slurmd.pid" "$cluster/slurmctld.pid"; do
    if [[ -f "$f" ]]; then
      pid="$(cat "$f")"
      kill "$pid" 2> /dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2> /dev/null || true
    fi
  done
  rm -rf "$tmp"
}
trap stop_cluster EXIT
fail() {
  echo "FAIL: $*" >&2
  for log in "$cluster"/*.log "$tmp"/w*/logs/*; do [[ -f "$log" ]] && { echo "--- $log"; tail -n 20 "$log"; }; done >&2
  exit 1
}

# Two free TCP ports on 127.0.0.1, so that clusters of several test runs on one machine do not meet.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
host="$(hostname)"
user="$(id -un)"
node="$(/usr/sbin/slurmd -C | sed -nE '1{s/ RealMemory=[0-9]+//; s/ UpTime=.*//; p}')"
memory=$(( $(free -m | awk '/^Mem:/ {print $2}') * 8 / 10 ))
cat > "$cluster/slurm.conf" << CONF
ClusterName=city3dtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/none
CredType=cred/none
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/slurmctld.log
SlurmdLogFile=$cluster/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1000
SchedulerParameters=sched_interval=1
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
ReturnToService=2
KillWait=5
MaxArraySize=1000
MaxJobCount=10000
$node NodeAddr=127.0.0.1 RealMemory=$memory State=UNKNOWN
PartitionName=city3d Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$cluster/slurm.conf"
/usr/sbin/slurmctld -i
/usr/sbin/slurmd
for _ in $(seq 100); do
  sinfo -h -o %t 2> /dev/null | grep -qE '^idle' && break
  sleep 0.3
done
sinfo -h -o %t | grep -qE '^idle' || fail "the private cluster did not come up"
echo "cluster up: $(sinfo -h -o '%N %c CPUs %t')"

reconstruct_args=("$data/ahn3_cropped_1.las" "$data/ahn3_cropped_2.las" -f "$data/footprints/bgt_pand_laz_area.gpkg"
  --id-field gml_id --cityjsonseq --gpkg --block-size 100 -v)

# What ogrinfo reads from a GeoPackage: every layer, field and feature (values and geometry).
gpkg_dump() { ogrinfo -ro -al -q "$1" || fail "ogrinfo cannot read $1"; }

same_outputs() {  # the outputs of two folders: byte for byte, the reports up to their timings
  local a="$1" b="$2" f
  for f in buildings.city.json buildings.city.jsonl buildings.gpkg; do
    cmp "$a/$f" "$b/$f" || fail "$f of $b differs from $a"
  done
  if command -v ogrinfo > /dev/null; then
    diff <(gpkg_dump "$a/buildings.gpkg") <(gpkg_dump "$b/buildings.gpkg") > /dev/null ||
      fail "buildings.gpkg of $b reads differently from $a"
  fi
  diff -r "$a/models" "$b/models" > /dev/null || fail "the models of $b differ from $a"
  for f in report.csv report.json; do
    diff <(sed -E 's/,[0-9]+\.[0-9]{4},[0-9]+\.[0-9]{4}$//; s/"(cpu_)?seconds":[0-9.]+//g' "$a/$f") \
      <(sed -E 's/,[0-9]+\.[0-9]{4},[0-9]+\.[0-9]{4}$//; s/"(cpu_)?seconds":[0-9.]+//g' "$b/$f") > /dev/null || fail "$f of $b differs from $a"
  done
  # report.html up to each building's seconds ("t" in its data).
  grep -q "city3d report ready" "$a/report.html" || fail "$a/report.html is not a report"
  diff <(sed -E 's/"t":(null|-?[0-9.]+)/"t":S/g' "$a/report.html") \
    <(sed -E 's/"t":(null|-?[0-9.]+)/"t":S/g' "$b/report.html") > /dev/null || fail "report.html of $b differs from $a"
  local n; n="$(find "$a/models" -name "*.obj" | wc -l)"
  [[ "$n" -eq 160 ]] || fail "$a holds $n OBJ models, not 160"
}

# One process.
"$city3d" reconstruct "${reconstruct_args[@]}" -j 2 -q --no-progress -o "$tmp/single"

# 4 shards as a job array, 2 running at a time, then the merge.
"$repo/scripts/slurm/city3d-slurm" submit --work "$tmp/w1" --output "$tmp/merged1" --shards 4 --city3d "$city3d" \
  --sbatch "--cpus-per-task=1" --wait -- "${reconstruct_args[@]}" || fail "the sharded run failed"
same_outputs "$tmp/single" "$tmp/merged1"
echo "4 shards + merge: identical to one process"

# Again, two shards per array task (task 2 runs shards 3 and 4), with shard 3 killed (-9) once it has
# finished a few buildings: task 2 goes on with shard 4, then fails, so the merge does not run.
cat > "$tmp/city3d-killed-once" << WRAPPER
#!/usr/bin/env bash
if [[ " \$* " == *" --shard 3/4 "* && ! -e "$tmp/killed" ]]; then
  touch "$tmp/killed"
  out="\${@: -1}"
  "$city3d" "\$@" & pid=\$!
  while kill -0 \$pid 2> /dev/null && [[ \$(cat "\$out/resume.journal" 2> /dev/null | wc -l) -lt 4 ]]; do sleep 0.02; done
  kill -9 \$pid
  wait \$pid
  exit \$?
fi
exec "$city3d" "\$@"
WRAPPER
chmod +x "$tmp/city3d-killed-once"
if "$repo/scripts/slurm/city3d-slurm" submit --work "$tmp/w2" --output "$tmp/merged2" --shards 4 --per-task 2 \
  --city3d "$tmp/city3d-killed-once" --sbatch "--cpus-per-task=1" --wait -- "${reconstruct_args[@]}"; then
  fail "the merge ran although shard 3 was killed"
fi
[[ -f "$tmp/killed" && ! -f "$tmp/w2/shard-3/run.json" && -f "$tmp/w2/shard-3/resume.journal" ]] ||
  fail "shard 3 was not killed in the middle of its work"
for k in 1 2 4; do [[ -f "$tmp/w2/shard-$k/run.json" ]] || fail "shard $k did not finish"; done
[[ ! -e "$tmp/merged2/run.json" ]] || fail "a merged output exists although a shard was killed"
status="$("$repo/scripts/slurm/city3d-slurm" status --work "$tmp/w2")"
echo "$status"
grep -q "not finished: 3 " <<< "$status" || fail "status does not name shard 3"
resubmitted="$("$repo/scripts/slurm/city3d-slurm" resubmit --work "$tmp/w2" --wait)" || fail "the re-submission failed"
echo "$resubmitted"
job="$(sed -nE 's/.*shard tasks 2 of job ([0-9]+).*/\1/p' <<< "$resubmitted")"
[[ -n "$job" ]] || fail "the re-submission did not submit only task 2 (shards 3 and 4)"
# In the re-submitted task, shard 3 resumes from its journal and finished shard 4 is only re-assembled.
section() { awk -v k="$1" '$0 ~ "city3d-slurm: shard " k "/4" {on = 1; next} /city3d-slurm: shard [0-9]+\/4/ {on = 0} on' \
  "$tmp/w2/logs/shards-${job}_2.out"; }
# Each section is read whole before it is searched: `section K | grep -q` under pipefail fails when grep
# stops at its match while awk still writes (SIGPIPE), as it did once in CI.
shard3="$(section 3)" shard4="$(section 4)"
grep -q "resume: [1-9][0-9]* finished buildings" <<< "$shard3" || fail "shard 3 did not resume from its journal"
grep -q "resume: [1-9][0-9]* finished buildings" <<< "$shard4" || fail "shard 4 was not only re-assembled from its journal"
if grep -q "points streamed" <<< "$shard4"; then fail "shard 4 read its tiles again"; fi
same_outputs "$tmp/single" "$tmp/merged2"
echo "shard 3 killed, re-submitted, resumed + merge: identical to one process"
