# Sourced by the GPU checks (check_opencl_device.sh, throughput.sh) after they set $out: the
# summary file and say(), and the OpenCL vendor list. The ICD loader reads the vendor list from
# OCL_ICD_VENDORS: the GPU driver's library beside whatever the system lists (PoCL).
summary=$out/summary.txt
: >"$summary"
say() { echo "$*" | tee -a "$summary"; }
vendors=$out/vendors
mkdir -p "$vendors"
nv=$(ldconfig -p | awk '/libnvidia-opencl\.so\.1 /{print $NF; exit}')
[ -n "$nv" ] && echo "$nv" >"$vendors/nvidia.icd"
cp /etc/OpenCL/vendors/*.icd "$vendors/" 2>/dev/null
export OCL_ICD_VENDORS=$vendors
