// The device management of chapter 2: VciServer, the device manager, the device list with its
// change event, and the devices it enumerates.
using System;
using System.Collections;
using System.Threading;
using Ixxat.Vci3.Bal;

namespace Ixxat.Vci3
{
  public enum VciBusType : byte { Reserved = 0, Can = 1, Lin = 2, FlexRay = 3, KLine = 4 }

  // One bus connection of a device (IVciDevice.Equipment): entry 0 is bus connection 1.
  public struct VciCtrlInfo
  {
    readonly VciBusType busType;
    readonly byte controllerType;
    internal VciCtrlInfo(ushort word) { busType = (VciBusType)(word >> 8); controllerType = (byte)word; }
    public VciBusType BusType { get { return busType; } }
    // Bal.Can.CanCtrlType for a CAN connection, Bal.Lin.LinCtrlType for a LIN one.
    public byte ControllerType { get { return controllerType; } }
    public override string ToString() { return BusType + " controller " + controllerType; }
  }

  public interface IVciDevice : IDisposable
  {
    string Description { get; }
    string Manufacturer { get; }
    long VciObjectId { get; }
    Guid DeviceClass { get; }
    // A boxed Guid whose first bytes are the serial number as text ("HW" and digits).
    object UniqueHardwareId { get; }
    Version DriverVersion { get; }
    Version HardwareVersion { get; }
    VciCtrlInfo[] Equipment { get; }
    IBalObject OpenBusAccessLayer();
  }

  public interface IVciDeviceList : IEnumerable, IDisposable
  {
    void AssignEvent(AutoResetEvent e);
    void AssignEvent(ManualResetEvent e);
  }

  public interface IVciDeviceManager : IDisposable
  {
    IVciDeviceList GetDeviceList();
  }

  public static class VciServer
  {
    public static IVciDeviceManager GetDeviceManager()
    {
      Native.Check(Native.vciInitialize(), "VciServer.GetDeviceManager");
      return new DeviceManager();
    }

    // The version of the VCI this assembly implements (the .NET API of VCI 3).
    public static Version Version { get { return new Version(3, 5); } }
  }

  internal sealed class DeviceManager : IVciDeviceManager
  {
    bool disposed;
    public IVciDeviceList GetDeviceList()
    {
      if (disposed) throw VciException.Disposed("IVciDeviceManager");
      return new DeviceList();
    }
    public void Dispose() { disposed = true; }
  }

  internal sealed class DeviceList : IVciDeviceList
  {
    readonly object gate = new object();
    EventWaitHandle assigned;
    Thread watcher;
    IntPtr watchEnum;
    volatile bool disposed;

    public IEnumerator GetEnumerator()
    {
      if (disposed) throw VciException.Disposed("IVciDeviceList");
      return new DeviceEnumerator();
    }

    public void AssignEvent(AutoResetEvent e) { Assign(e); }
    public void AssignEvent(ManualResetEvent e) { Assign(e); }

    void Assign(EventWaitHandle e)
    {
      if (disposed) throw VciException.Disposed("IVciDeviceList");
      if (e == null) throw new VciException(Native.E_INVALIDARG, "IVciDeviceList.AssignEvent: the event is null");
      lock (gate)
      {
        assigned = e;
        if (watcher != null) return;
        IntPtr h;
        Native.Check(Native.vciEnumDeviceOpen(out h), "IVciDeviceList.AssignEvent");
        watchEnum = h;
        watcher = new Thread(Watch) { IsBackground = true, Name = "vci-device-list" };
        watcher.Start();
      }
    }

    // Signals the assigned event on every change of canemud's adapter list.
    void Watch()
    {
      while (!disposed)
      {
        uint hr = Native.vciEnumDeviceWaitEvent(watchEnum, 100);
        if (disposed) break;
        if (hr == Native.VCI_OK)
        {
          Native.vciEnumDeviceReset(watchEnum);  // the next wait waits for the next change
          EventWaitHandle e;
          lock (gate) e = assigned;
          if (e != null) e.Set();
        }
        else if (hr != Native.E_TIMEOUT) Thread.Sleep(100);  // canemud gone: try again later
      }
    }

    public void Dispose()
    {
      Thread w;
      lock (gate) { if (disposed) return; disposed = true; w = watcher; }
      if (w != null) { w.Join(); Native.vciEnumDeviceClose(watchEnum); }
    }
  }

  internal sealed class DeviceEnumerator : IEnumerator, IDisposable
  {
    IntPtr handle;
    byte[] current;

    public DeviceEnumerator()
    {
      Native.Check(Native.vciEnumDeviceOpen(out handle), "IVciDeviceList.GetEnumerator");
    }

    public bool MoveNext()
    {
      if (handle == IntPtr.Zero) throw VciException.Disposed("the device enumerator");
      var info = new byte[Native.DeviceInfoSize];
      uint hr = Native.vciEnumDeviceNext(handle, info);
      if (hr == Native.E_NO_MORE_ITEMS) { current = null; return false; }
      Native.Check(hr, "IEnumerator.MoveNext");
      current = info;
      return true;
    }

    // A new device object on every read (chapter 2.2).
    public object Current
    {
      get
      {
        if (current == null)
          throw new InvalidOperationException("IEnumerator.Current: MoveNext has not found a device (call MoveNext first; it returned false at the end)");
        return new VciDevice((byte[])current.Clone());
      }
    }

    public void Reset()
    {
      if (handle == IntPtr.Zero) throw VciException.Disposed("the device enumerator");
      Native.Check(Native.vciEnumDeviceReset(handle), "IEnumerator.Reset");
      current = null;
    }

    public void Dispose()
    {
      if (handle != IntPtr.Zero) { Native.vciEnumDeviceClose(handle); handle = IntPtr.Zero; }
    }

    ~DeviceEnumerator() { Dispose(); }
  }

  internal sealed class VciDevice : IVciDevice
  {
    readonly byte[] info;
    bool disposed;

    internal VciDevice(byte[] info) { this.info = info; }

    public long VciObjectId { get { return BitConverter.ToInt64(info, 0); } }
    public Guid DeviceClass { get { return GuidAt(8); } }
    public Version DriverVersion { get { return new Version(info[24], info[25], Bytes.U16(info, 26), Bytes.U16(info, 302)); } }
    public Version HardwareVersion { get { return new Version(info[29], info[30], info[31], info[28]); } }
    public object UniqueHardwareId { get { return GuidAt(32); } }
    public string Description { get { return Bytes.Latin1(info, 48, 128); } }
    public string Manufacturer { get { return Bytes.Latin1(info, 176, 126); } }

    Guid GuidAt(int at)
    {
      var g = new byte[16];
      Buffer.BlockCopy(info, at, g, 0, 16);
      return new Guid(g);
    }

    public VciCtrlInfo[] Equipment
    {
      get
      {
        IntPtr dev = Open("IVciDevice.Equipment");
        try
        {
          var caps = new byte[Native.DeviceCapsSize];
          Native.Check(Native.vciDeviceGetCaps(dev, caps), "IVciDevice.Equipment");
          var list = new VciCtrlInfo[Math.Min((int)Bytes.U16(caps, 0), 32)];
          for (int i = 0; i < list.Length; i++) list[i] = new VciCtrlInfo(Bytes.U16(caps, 2 + 2 * i));
          return list;
        }
        finally { Native.vciDeviceClose(dev); }
      }
    }

    internal IntPtr Open(string what)
    {
      if (disposed) throw VciException.Disposed("IVciDevice");
      long id = VciObjectId;
      IntPtr dev;
      uint hr = Native.vciDeviceOpen(ref id, out dev);
      if (hr != Native.VCI_OK)
        throw new VciException(hr, what + ": the device " + Description + " (VciObjectId " + id +
                                   ") cannot be opened: " + Native.Text(hr));
      return dev;
    }

    public IBalObject OpenBusAccessLayer()
    {
      return new BalObject(Open("IVciDevice.OpenBusAccessLayer"), Description);
    }

    public void Dispose() { disposed = true; }
    public override string ToString() { return Description; }
  }
}
